#include "ffcube/core/log.hpp"

#include <atomic>
#include <cstdio>
#include <mutex>

namespace ffcube {
namespace {
std::atomic<LogLevel> g_level{LogLevel::Normal};
std::mutex g_mutex;

void emit(const char* prefix, const std::string& message) {
    std::lock_guard lock(g_mutex);
    std::fprintf(stderr, "%s%s\n", prefix, message.c_str());
    std::fflush(stderr);
}
}  // namespace

void set_log_level(LogLevel level) { g_level = level; }
LogLevel log_level() { return g_level; }
void log_warning(const std::string& message) { emit("ffcube: warning: ", message); }
void log_info(const std::string& message) { emit("ffcube: ", message); }
void log_verbose(const std::string& message) { emit("ffcube: ", message); }

}  // namespace ffcube
