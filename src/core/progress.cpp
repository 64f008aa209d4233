#include "ffcube/core/progress.hpp"

#include <unistd.h>

#include <cstdio>

namespace ffcube {

Progress::Progress(std::string what, std::uint64_t total, bool enabled)
    : what_(std::move(what)), total_(total), enabled_(enabled), tty_(isatty(STDERR_FILENO) != 0) {}

Progress::~Progress() { finish(); }

void Progress::add(std::uint64_t n) {
    done_ += n;
    if (!enabled_) return;
    const double t = watch_.seconds();
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
    if (enabled_ && last_print_ > 0.0) print(true);
}

void Progress::print(bool final_line) {
    const double t = watch_.seconds();
    const std::uint64_t done = done_;
    const double rate = t > 0 ? static_cast<double>(done) / t : 0.0;
    const double eta = rate > 0 ? static_cast<double>(total_ - std::min(done, total_)) / rate : 0.0;
    std::fprintf(stderr, "%s%s: %llu/%llu (%.1f%%), %.1f/s, %s %.0f s%s", tty_ ? "\r" : "", what_.c_str(),
                 static_cast<unsigned long long>(done), static_cast<unsigned long long>(total_),
                 total_ ? 100.0 * static_cast<double>(done) / static_cast<double>(total_) : 100.0, rate,
                 final_line ? "took" : "ETA", final_line ? t : eta, (tty_ && !final_line) ? "   " : "\n");
    std::fflush(stderr);
}

}  // namespace ffcube
