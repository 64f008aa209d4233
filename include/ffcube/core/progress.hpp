// Progress for long runs on stderr: done/total, rate, ETA. Thread-safe; prints at most about
// once per second, with '\r' updates on a terminal and plain lines otherwise. Silent when quiet.
#pragma once

#include <atomic>
#include <cstdint>
#include <mutex>
#include <string>

#include "ffcube/core/timer.hpp"

namespace ffcube {

class Progress {
public:
    Progress(std::string what, std::uint64_t total, bool enabled);
    ~Progress();
    Progress(const Progress&) = delete;
    Progress& operator=(const Progress&) = delete;

    void add(std::uint64_t n = 1);
    void finish();

private:
    void print(bool final_line);

    std::string what_;
    std::uint64_t total_;
    bool enabled_;
    bool tty_;
    std::atomic<std::uint64_t> done_{0};
    std::mutex mutex_;
    Stopwatch watch_;
    double last_print_ = 0.0;
    bool finished_ = false;
};

}  // namespace ffcube
