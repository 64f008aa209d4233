// Wall-clock timing for reports (never for tests: tests assert results, not speed).
#pragma once

#include <chrono>

namespace ffcube {

class Stopwatch {
public:
    Stopwatch() : start_(std::chrono::steady_clock::now()) {}
    void restart() { start_ = std::chrono::steady_clock::now(); }
    // Seconds since construction or the last restart().
    double seconds() const {
        return std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
    }

private:
    std::chrono::steady_clock::time_point start_;
};

// Adds the lifetime of the scope to an accumulator (seconds).
class ScopedTimer {
public:
    explicit ScopedTimer(double& sink) : sink_(sink) {}
    ~ScopedTimer() { sink_ += watch_.seconds(); }
    ScopedTimer(const ScopedTimer&) = delete;
    ScopedTimer& operator=(const ScopedTimer&) = delete;

private:
    double& sink_;
    Stopwatch watch_;
};

}  // namespace ffcube
