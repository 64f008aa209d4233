// Diagnostics on stderr. Results never go to stderr; progress and warnings do.
#pragma once

#include <fmt/format.h>

#include <string>

namespace ffcube {

enum class LogLevel { Quiet = 0, Normal = 1, Verbose = 2 };

void set_log_level(LogLevel level);
LogLevel log_level();

// Warnings are printed even with --quiet: they say the input was unusual or a default was taken.
void log_warning(const std::string& message);
void log_info(const std::string& message);
void log_verbose(const std::string& message);

template <typename... Args>
void warn(fmt::format_string<Args...> f, Args&&... args) {
    log_warning(fmt::format(f, std::forward<Args>(args)...));
}
template <typename... Args>
void info(fmt::format_string<Args...> f, Args&&... args) {
    if (log_level() >= LogLevel::Normal) log_info(fmt::format(f, std::forward<Args>(args)...));
}
template <typename... Args>
void verbose(fmt::format_string<Args...> f, Args&&... args) {
    if (log_level() >= LogLevel::Verbose) log_verbose(fmt::format(f, std::forward<Args>(args)...));
}

}  // namespace ffcube
