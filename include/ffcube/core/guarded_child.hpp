// Runs a function on untrusted input in a forked child process with a wall-clock limit and an
// address-space cap, and brings back the bytes it returns through a pipe. For third-party
// parsers (assimp) that may crash, loop forever or allocate what a header claims: whatever the
// child does, the parent gets an answer (docs/robustness.md, "Third-party parsers").
//
// The child is a fork of the caller, so the function sees the caller's memory as it was. It
// runs with RLIMIT_AS set to its address space at the fork plus `extra_address_space`, RLIMIT_CPU
// as a second stop, and SIGKILL should the parent die. It ends with _Exit (no destructors, no
// atexit handlers, no flush of the parent's stdio). The parent reads the pipe while the child
// writes (no size limit on the pipe), retries on EINTR, kills the child at the deadline and
// always reaps it.
//
// glibc's malloc is safe in a forked child of a threaded process; other locks held by the
// caller's other threads at the fork are not, so call this before starting threads that hold
// locks the function needs (ffcube loads scenes before its worker threads start).
#pragma once

#include <chrono>
#include <cstdint>
#include <functional>
#include <string>

#include "ffcube/core/error_transport.hpp"

namespace ffcube {

struct ChildLimits {
    std::chrono::milliseconds wall{10000};
    // Address space the child may map beyond what it had at the fork (RLIMIT_AS is a total, and a
    // process built with AddressSanitizer starts with terabytes reserved for its shadow).
    std::uint64_t extra_address_space = std::uint64_t(1) << 30;
};

struct ChildResult {
    enum class End {
        returned,       // the function returned: `payload`
        threw,          // it threw: `error_kind`, `error_message` (std::bad_alloc: out_of_memory)
        out_of_memory,  // an allocation failed under the cap (then it threw or died)
        signalled,      // killed by `signal` (a crash), after no allocation failed
        timed_out,      // still running at the deadline: killed
        exited,         // ended with `status` without saying why (e.g. a sanitizer's report)
    };
    End end = End::exited;
    std::string payload;
    ErrorKind error_kind = ErrorKind::other;
    std::string error_message;
    int signal = 0;
    int status = 0;
    double seconds = 0.0;  // wall time until the child ended or was killed
};

// IoError when no child can be started (pipe, fork).
ChildResult run_guarded(const std::function<std::string()>& fn, const ChildLimits& limits);

}  // namespace ffcube
