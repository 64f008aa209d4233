// Progress for long runs on stderr: done/total, rate, ETA. Thread-safe; prints at most every
// 0.25 s on a terminal ('\r' updates) and every 2 s otherwise (plain lines). Silent when quiet.
// The rate and the ETA are measured from the first add(), and no ETA is given before a second
// of work ("ETA soon known"). A bar that never reached its first line prints nothing, unless the
// environment says FFCUBE_PROGRESS=always: then every bar prints its first step and its end.
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
    std::atomic<bool> started_{false};  // add() was called: first_time_, first_done_ set
    double first_time_ = 0.0;
    std::uint64_t first_done_ = 0;
    bool finished_ = false;
};

}  // namespace ffcube
