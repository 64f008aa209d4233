#include "ffcube/core/guarded_child.hpp"

#include <fcntl.h>
#include <poll.h>
#include <signal.h>
#include <sys/mman.h>
#include <sys/prctl.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <fmt/format.h>

#include <atomic>
#include <cerrno>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <new>

#include "ffcube/core/error.hpp"

namespace ffcube {
namespace {

using Clock = std::chrono::steady_clock;

// The child's frame on the pipe: tag, error kind, payload length, payload.
enum : std::uint8_t { kReturned = 1, kThrew = 2 };
constexpr std::size_t kFrameHead = 1 + 4 + 8;

// One page shared with the parent (mapped before the fork): set by the child when an
// allocation failed, so a child that then dies of the failure (assimp dereferencing what a
// failed allocation left, or abort()) is still reported as having hit its cap.
struct SharedFlags {
    std::atomic<int> allocation_failed{0};
};
SharedFlags* g_child_flags = nullptr;  // in the child only

void on_allocation_failure() {
    if (g_child_flags != nullptr) g_child_flags->allocation_failed.store(1);
    std::set_new_handler(nullptr);  // operator new retries once more, then throws std::bad_alloc
}

void write_all(int fd, const void* data, std::size_t size) {
    const char* p = static_cast<const char*>(data);
    while (size > 0) {
        const ssize_t n = ::write(fd, p, size);
        if (n < 0 && errno == EINTR) continue;
        if (n <= 0) std::_Exit(3);  // the parent is gone, or the pipe broke: nothing to tell
        p += n;
        size -= static_cast<std::size_t>(n);
    }
}

void write_frame(int fd, std::uint8_t tag, ErrorKind kind, const std::string& payload) {
    unsigned char head[kFrameHead];
    head[0] = tag;
    const auto k = static_cast<std::uint32_t>(kind);
    const auto n = static_cast<std::uint64_t>(payload.size());
    std::memcpy(head + 1, &k, 4);
    std::memcpy(head + 5, &n, 8);
    write_all(fd, head, sizeof head);
    write_all(fd, payload.data(), payload.size());
}

// The pages this process has mapped (VmSize), from /proc/self/statm; 0 when unknown. No
// allocation: called in the child right after the fork.
std::uint64_t mapped_bytes() {
    const int fd = ::open("/proc/self/statm", O_RDONLY | O_CLOEXEC);
    if (fd < 0) return 0;
    char buf[64] = {};
    const ssize_t n = ::read(fd, buf, sizeof buf - 1);
    ::close(fd);
    if (n <= 0) return 0;
    std::uint64_t pages = 0;
    for (ssize_t i = 0; i < n && buf[i] >= '0' && buf[i] <= '9'; ++i) pages = pages * 10 + std::uint64_t(buf[i] - '0');
    return pages * static_cast<std::uint64_t>(::sysconf(_SC_PAGESIZE));
}

[[noreturn]] void child_main(int fd, pid_t parent, SharedFlags* flags, const std::function<std::string()>& fn,
                             const ChildLimits& limits) {
    // Killed with the parent (ffcube interrupted): never an orphan still parsing.
    ::prctl(PR_SET_PDEATHSIG, SIGKILL);
    if (::getppid() != parent) std::_Exit(1);
    // The pipe as fd 3 and nothing else of the parent's: a child that holds the write ends of
    // other pipes or sockets (a sibling's, a hemicube worker's) delays their end of stream.
    if (fd != 3) {
        ::dup2(fd, 3);
        fd = 3;
    }
    ::close_range(4, ~0u, 0);
    ::signal(SIGPIPE, SIG_IGN);
    ::signal(SIGINT, SIG_IGN);  // the parent decides; a Ctrl-C reaches it and it kills us
    const rlimit no_core{0, 0};
    ::setrlimit(RLIMIT_CORE, &no_core);  // a crash here is reported, not dumped into the cwd
    const std::uint64_t base = mapped_bytes();
    if (base > 0) {
        const rlim_t cap = static_cast<rlim_t>(base + limits.extra_address_space);
        const rlimit as{cap, cap};
        ::setrlimit(RLIMIT_AS, &as);
    }
    // CPU time as a second stop should the parent's clock not get to kill us (SIGXCPU).
    const auto cpu = static_cast<rlim_t>(limits.wall.count() / 1000 + 2);
    const rlimit cpu_limit{cpu, cpu + 1};
    ::setrlimit(RLIMIT_CPU, &cpu_limit);
    g_child_flags = flags;
    std::set_new_handler(on_allocation_failure);
    try {
        const std::string payload = fn();
        write_frame(fd, kReturned, ErrorKind::other, payload);
    } catch (const std::bad_alloc&) {
        flags->allocation_failed.store(1);
        write_frame(fd, kThrew, ErrorKind::out_of_memory, std::string());
    } catch (const std::exception& e) {
        try {
            write_frame(fd, kThrew, error_kind(e), e.what());
        } catch (...) {
            std::_Exit(4);
        }
    } catch (...) {
        write_frame(fd, kThrew, ErrorKind::other, "unknown exception");
    }
    std::_Exit(0);
}

// Kills and reaps the child on every way out of the parent's side (an exception included).
class ChildGuard {
public:
    explicit ChildGuard(pid_t pid) : pid_(pid) {}
    ~ChildGuard() {
        if (pid_ > 0) {
            ::kill(pid_, SIGKILL);
            int status = 0;
            while (::waitpid(pid_, &status, 0) < 0 && errno == EINTR) {
            }
        }
    }
    ChildGuard(const ChildGuard&) = delete;
    ChildGuard& operator=(const ChildGuard&) = delete;
    pid_t pid() const { return pid_; }
    void reaped() { pid_ = -1; }

private:
    pid_t pid_;
};

class Fd {
public:
    explicit Fd(int fd) : fd_(fd) {}
    ~Fd() {
        if (fd_ >= 0) ::close(fd_);
    }
    Fd(const Fd&) = delete;
    Fd& operator=(const Fd&) = delete;
    int get() const { return fd_; }
    void close() {
        if (fd_ >= 0) ::close(fd_);
        fd_ = -1;
    }

private:
    int fd_;
};

class SharedPage {
public:
    SharedPage() {
        void* p = ::mmap(nullptr, sizeof(SharedFlags), PROT_READ | PROT_WRITE, MAP_SHARED | MAP_ANONYMOUS, -1, 0);
        if (p == MAP_FAILED) throw IoError(fmt::format("guarded child: mmap failed: {}", std::strerror(errno)));
        flags_ = new (p) SharedFlags();
    }
    ~SharedPage() { ::munmap(flags_, sizeof(SharedFlags)); }
    SharedPage(const SharedPage&) = delete;
    SharedPage& operator=(const SharedPage&) = delete;
    SharedFlags* get() const { return flags_; }

private:
    SharedFlags* flags_;
};

}  // namespace

ChildResult run_guarded(const std::function<std::string()>& fn, const ChildLimits& limits) {
    SharedPage shared;
    int p[2];
    if (::pipe2(p, O_CLOEXEC) != 0) throw IoError(fmt::format("guarded child: pipe failed: {}", std::strerror(errno)));
    Fd read_end(p[0]), write_end(p[1]);
    const pid_t parent = ::getpid();
    std::fflush(nullptr);  // nothing buffered twice
    const auto start = Clock::now();
    const pid_t pid = ::fork();
    if (pid < 0) throw IoError(fmt::format("guarded child: fork failed: {}", std::strerror(errno)));
    if (pid == 0) child_main(write_end.get(), parent, shared.get(), fn, limits);
    ChildGuard child(pid);
    write_end.close();  // else the parent never sees the end of the stream

    const auto deadline = start + limits.wall;
    std::string bytes;
    bool eof = false, reaped = false, timed_out = false;
    int status = 0;
    char buffer[1 << 16];
    for (;;) {
        // Rounded up: truncation made `left` 0 up to a millisecond before the deadline, and the
        // child was then killed early (GuardedChild.ALoopIsKilledAtTheDeadline saw 0.29994 s of 0.3).
        const auto left = std::chrono::ceil<std::chrono::milliseconds>(deadline - Clock::now()).count();
        if (left <= 0) {
            timed_out = true;
            break;
        }
        if (!eof) {
            pollfd pfd{read_end.get(), POLLIN, 0};
            const int r = ::poll(&pfd, 1, static_cast<int>(std::min<long long>(left, 1000)));
            if (r < 0 && errno != EINTR) throw IoError(fmt::format("guarded child: poll failed: {}", std::strerror(errno)));
            if (r <= 0) continue;
            const ssize_t n = ::read(read_end.get(), buffer, sizeof buffer);
            if (n < 0 && (errno == EINTR || errno == EAGAIN)) continue;
            if (n < 0) throw IoError(fmt::format("guarded child: read failed: {}", std::strerror(errno)));
            if (n == 0) eof = true;
            else bytes.append(buffer, static_cast<std::size_t>(n));
            continue;
        }
        // End of stream: the child is exiting. It could still hang in exit (it should not, with
        // _Exit), so the deadline holds here too.
        const pid_t w = ::waitpid(pid, &status, WNOHANG);
        if (w == pid) {
            reaped = true;
            break;
        }
        if (w < 0 && errno == EINTR) continue;
        if (w < 0) break;  // ECHILD (SIGCHLD ignored by the embedding program): status unknown
        ::usleep(1000);
    }
    if (timed_out) ::kill(pid, SIGKILL);
    if (!reaped) {
        while (::waitpid(pid, &status, 0) < 0 && errno == EINTR) {
        }
        reaped = true;
    }
    child.reaped();

    ChildResult out;
    out.seconds = std::chrono::duration<double>(Clock::now() - start).count();
    const bool ran_out_of_memory = shared.get()->allocation_failed.load() != 0;
    if (timed_out) {
        out.end = ChildResult::End::timed_out;
        return out;
    }
    // A complete frame is what the function did, however the child then ended.
    if (bytes.size() >= kFrameHead) {
        std::uint32_t kind = 0;
        std::uint64_t n = 0;
        std::memcpy(&kind, bytes.data() + 1, 4);
        std::memcpy(&n, bytes.data() + 5, 8);
        if (n == bytes.size() - kFrameHead) {
            if (bytes[0] == kReturned) {
                out.end = ChildResult::End::returned;
                out.payload = bytes.substr(kFrameHead);
                return out;
            }
            if (bytes[0] == kThrew) {
                out.end = static_cast<ErrorKind>(kind) == ErrorKind::out_of_memory ? ChildResult::End::out_of_memory
                                                                                 : ChildResult::End::threw;
                out.error_kind = static_cast<ErrorKind>(kind);
                out.error_message = bytes.substr(kFrameHead);
                return out;
            }
        }
    }
    if (ran_out_of_memory) {
        out.end = ChildResult::End::out_of_memory;
    } else if (WIFSIGNALED(status)) {
        // SIGXCPU: RLIMIT_CPU, the second stop of the time limit.
        out.end = WTERMSIG(status) == SIGXCPU ? ChildResult::End::timed_out : ChildResult::End::signalled;
        out.signal = WTERMSIG(status);
    } else {
        out.end = ChildResult::End::exited;
        out.status = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
    }
    return out;
}

}  // namespace ffcube
