#include "ffcube/core/progress.hpp"

#include <unistd.h>

#include <cstdio>
#include <cstdlib>
#include <cstring>

namespace ffcube {
namespace {

// FFCUBE_PROGRESS=always: every bar prints a line at its first step and its final line, however
// short the run (tests check that each phase shows its bar; logs of small runs show every phase).
bool always() {
    static const bool a = [] {
        const char* v = std::getenv("FFCUBE_PROGRESS");
        return v && std::strcmp(v, "always") == 0;
    }();
    return a;
}

// No ETA until the work has run this long since its first step: the first steps' rate (a phase's
// setup, a slow first block) says little about the rest.
constexpr double kEtaAfterSeconds = 1.0;

}  // namespace

Progress::Progress(std::string what, std::uint64_t total, bool enabled)
    : what_(std::move(what)), total_(total), enabled_(enabled), tty_(isatty(STDERR_FILENO) != 0) {}

Progress::~Progress() { finish(); }

void Progress::add(std::uint64_t n) {
    const std::uint64_t done = done_ += n;
    if (!enabled_) return;
    const double t = watch_.seconds();
    if (!started_.load(std::memory_order_relaxed)) {
        std::lock_guard lock(mutex_);
        if (!started_) {
            // The rate is measured from the first step, not from construction: the time before it
            // (opening files, a pass's setup) is no measure of the work left.
            first_time_ = t;
            first_done_ = done - n;
            started_ = true;
            if (always()) {
                last_print_ = t > 0 ? t : 1e-9;
                print(false);
                return;
            }
        }
    }
    // Cheap unlocked pre-check; the lock keeps lines whole.
    if (t - last_print_ < (tty_ ? 0.25 : 2.0)) return;
    std::lock_guard lock(mutex_);
    if (t - last_print_ < (tty_ ? 0.25 : 2.0)) return;
    last_print_ = t;
    print(false);
}

void Progress::finish() {
    std::lock_guard lock(mutex_);
    if (finished_) return;
    finished_ = true;
    // Short runs print nothing: progress is for runs long enough to wonder about.
    if (enabled_ && (last_print_ > 0.0 || always())) print(true);
}

void Progress::print(bool final_line) {
    const double t = watch_.seconds();
    const std::uint64_t done = done_;
    const double span = t - first_time_;
    const std::uint64_t since = done > first_done_ ? done - first_done_ : 0;
    const double rate = span > 0 ? static_cast<double>(since) / span : 0.0;
    const double percent = total_ ? 100.0 * static_cast<double>(done) / static_cast<double>(total_) : 100.0;
    char tail[64];
    if (final_line)
        std::snprintf(tail, sizeof tail, "took %.0f s", t);
    else if (span >= kEtaAfterSeconds && rate > 0)
        std::snprintf(tail, sizeof tail, "ETA %.0f s", static_cast<double>(total_ - std::min(done, total_)) / rate);
    else
        std::snprintf(tail, sizeof tail, "ETA soon known");
    std::fprintf(stderr, "%s%s: %llu/%llu (%.1f%%), %.1f/s, %s%s", tty_ ? "\r" : "", what_.c_str(),
                 static_cast<unsigned long long>(done), static_cast<unsigned long long>(total_), percent, rate, tail,
                 (tty_ && !final_line) ? "   " : "\n");
    std::fflush(stderr);
}

}  // namespace ffcube
