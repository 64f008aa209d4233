#include "gl/process_engine.hpp"

#include <fmt/format.h>

#include <array>
#include <cerrno>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <exception>
#include <fstream>
#include <memory>
#include <span>
#include <string>

#include <sys/socket.h>
#include <sys/uio.h>
#include <sys/wait.h>
#include <unistd.h>

#include "ffcube/core/error.hpp"
#include "ffcube/core/error_transport.hpp"
#include "ffcube/gl/context.hpp"
#include "ffcube/scene/scene_blob.hpp"
#include "gl/gl_api.hpp"
#include "gl/hemicube_worker.hpp"

namespace ffcube {

// The wire protocol between a ProcessEngine and its child: fixed-size headers and raw arrays
// over a Unix socket pair (both ends are the same binary).
// SampledRow: a std::uint64_t point count m, then m Vec3 (the sender points) and m doubles (their
// weights) follow, bit for bit. SetScene: a std::uint64_t byte count and that many bytes of
// scene/scene_blob.hpp follow; the reply has no payload.
enum class Request : std::uint32_t { Row = 0, ItemBuffer = 1, SampledRow = 2, SetScene = 4 };
static_assert(sizeof(Vec3) == 3 * sizeof(double), "sender points go over the socket as three doubles each");
struct RequestMsg {
    Request kind;
    std::uint32_t patch;
};
struct ProcessEngine::Reply {
    std::uint32_t error;   // 0: payload follows; else an ErrorKind, and 'count' bytes of message follow
    std::uint64_t count;   // entries (row), pixels (item buffer), bytes (hello strings, error)
    // Work done for this reply: a row's HemicubeStats in their flat form (core/stats.hpp).
    std::array<std::uint64_t, stats::words<HemicubeStats>()> counts;
};
using ReplyMsg = ProcessEngine::Reply;

namespace {

// The other end of the socket is closed (EPIPE, ECONNRESET, or the end of the stream within a
// message): in the parent, the child has ended or is ending, and ProcessEngine::child_gone says
// how.
struct PeerGone : IoError {
    using IoError::IoError;
};

[[noreturn]] void socket_failed(const char* what, int err) {
    const std::string msg = fmt::format("hemicube worker socket: {} failed: {}", what, std::strerror(err));
    if (err == EPIPE || err == ECONNRESET) throw PeerGone(msg);
    throw IoError(msg);
}

void send_all(int fd, const void* data, std::size_t size) {
    const char* p = static_cast<const char*>(data);
    while (size > 0) {
        const ssize_t n = ::send(fd, p, size, MSG_NOSIGNAL);
        if (n < 0 && errno == EINTR) continue;
        if (n <= 0) socket_failed("send", errno);
        p += n;
        size -= static_cast<std::size_t>(n);
    }
}

// Returns false on a clean end of stream before any byte.
bool recv_all(int fd, void* data, std::size_t size) {
    char* p = static_cast<char*>(data);
    std::size_t got = 0;
    while (got < size) {
        const ssize_t n = ::recv(fd, p + got, size - got, 0);
        if (n < 0 && errno == EINTR) continue;
        if (n < 0) socket_failed("receive", errno);
        if (n == 0) {
            if (got == 0) return false;
            throw PeerGone("hemicube worker socket: truncated message");
        }
        got += static_cast<std::size_t>(n);
    }
    return true;
}

template <typename T>
void send_vector(int fd, const std::vector<T>& v) {
    if (!v.empty()) send_all(fd, v.data(), v.size() * sizeof(T));
}

// Sends the buffers back to back in one sendmsg: a row's header and arrays wake the reader once,
// where three sends could wake it three times (boxed blocker: 30,000 context switches a run
// became 20,000). A blocking Unix stream socket takes the whole message, waiting while the
// reader drains it; the loop finishes what a signal may cut short.
void send_parts(int fd, std::span<iovec> parts) {
    std::size_t first = 0;
    while (first < parts.size()) {
        msghdr m{};
        m.msg_iov = parts.data() + first;
        m.msg_iovlen = parts.size() - first;
        ssize_t n = ::sendmsg(fd, &m, MSG_NOSIGNAL);
        if (n < 0 && errno == EINTR) continue;
        if (n <= 0) socket_failed("send", errno);
        // Skip what went; a part sent in part keeps its rest.
        for (; first < parts.size() && static_cast<std::size_t>(n) >= parts[first].iov_len; ++first)
            n -= static_cast<ssize_t>(parts[first].iov_len);
        if (first < parts.size()) {
            parts[first].iov_base = static_cast<char*>(parts[first].iov_base) + n;
            parts[first].iov_len -= static_cast<std::size_t>(n);
        }
    }
}

// Sends the exception being handled: its class tag and message.
void send_current_error(int fd) {
    ErrorKind kind = ErrorKind::other;
    std::string what = "unknown exception";
    try {
        throw;
    } catch (const std::exception& e) {
        kind = error_kind(e);
        what = e.what();
    } catch (...) {
    }
    ReplyMsg r{static_cast<std::uint32_t>(kind), what.size(), {}};
    send_all(fd, &r, sizeof r);
    send_all(fd, what.data(), what.size());
}

[[noreturn]] void child_main(int fd, const Scene& scene, const ScenePieces& pieces, const HemicubeLayout& layout,
                             const HemicubeOptions& opt) {
    int code = 0;
    try {
        std::unique_ptr<GlContext> ctx = create_headless_context(opt.backend);
        ctx->make_current();
        // The scene drawn: the parent's (copy-on-write since the fork) until a SetScene brings
        // another, which this child then owns with its pieces.
        const Scene* current_scene = &scene;
        const ScenePieces* current_pieces = &pieces;
        std::unique_ptr<Scene> own_scene;
        std::unique_ptr<ScenePieces> own_pieces;
        auto worker = std::make_unique<Worker>(*ctx, *current_scene, *current_pieces, layout, opt);
        const std::string hello = ctx->backend() + '\n' + ctx->renderer();
        ReplyMsg h{0, hello.size(), {}};
        send_all(fd, &h, sizeof h);
        send_all(fd, hello.data(), hello.size());
        SparseRow row;
        std::vector<Vec3> points;
        std::vector<double> weights;
        RequestMsg req{};
        while (recv_all(fd, &req, sizeof req)) {
            try {
                ReplyMsg r{0, 0, {}};
                if (req.kind == Request::SetScene) {
                    std::uint64_t n = 0;
                    if (!recv_all(fd, &n, sizeof n)) break;
                    std::vector<std::uint8_t> blob(n);
                    if (n && !recv_all(fd, blob.data(), n)) break;
                    worker.reset();  // before the scene it refers to goes
                    auto next_scene = std::make_unique<Scene>(deserialize_scene(blob));
                    auto next_pieces = std::make_unique<ScenePieces>(prepare_pieces(next_scene->grids));
                    own_scene = std::move(next_scene);
                    own_pieces = std::move(next_pieces);
                    current_scene = own_scene.get();
                    current_pieces = own_pieces.get();
                    worker = std::make_unique<Worker>(*ctx, *current_scene, *current_pieces, layout, opt);
                    send_all(fd, &r, sizeof r);
                } else if (!worker) {
                    throw IoError("hemicube worker: no scene (the last scene sent could not be taken)");
                } else if (req.kind == Request::Row || req.kind == Request::SampledRow) {
                    points.clear();
                    weights.clear();
                    if (req.kind == Request::SampledRow) {
                        std::uint64_t m = 0;
                        if (!recv_all(fd, &m, sizeof m)) break;
                        FFCUBE_CHECK_MSG(m > 0 && m <= 4096, "hemicube worker: a sampled row without a sane point count");
                        points.resize(m);
                        weights.resize(m);
                        if (!recv_all(fd, points.data(), m * sizeof(Vec3)) || !recv_all(fd, weights.data(), m * sizeof(double)))
                            break;
                    }
                    HemicubeStats st;
                    worker->row(req.patch, points, weights, row, st);
                    r.counts = stats::to_words(st);
                    r.count = row.nnz();
                    std::array<iovec, 3> parts{{{&r, sizeof r},
                                                {row.col.data(), row.col.size() * sizeof(std::uint32_t)},
                                                {row.val.data(), row.val.size() * sizeof(double)}}};
                    send_parts(fd, parts);
                } else {
                    FFCUBE_CHECK_MSG(req.kind == Request::ItemBuffer, "hemicube worker: unknown request");
                    HemicubeStats ignored;
                    worker->render(req.patch, ignored);
                    r.count = worker->ids().size();
                    send_all(fd, &r, sizeof r);
                    send_vector(fd, worker->ids());
                }
            } catch (...) {
                send_current_error(fd);
            }
        }
        ctx->release_current();
    } catch (...) {
        try {
            send_current_error(fd);
        } catch (...) {
        }
        code = 1;
    }
    // No destructors of the parent's objects, no atexit handlers, no flush of inherited stdio.
    std::_Exit(code);
}

}  // namespace

bool can_fork_workers() {
    if (gl::context_created_in_process()) return false;
    std::ifstream status("/proc/self/status");
    std::string line;
    while (std::getline(status, line))
        if (line.rfind("Threads:", 0) == 0) return std::stoi(line.substr(8)) == 1;
    return false;
}

ProcessEngine::ProcessEngine(const Scene& scene, const ScenePieces& pieces, const HemicubeLayout& layout,
                             const HemicubeOptions& opt) {
    int sv[2];
    if (::socketpair(AF_UNIX, SOCK_STREAM | SOCK_CLOEXEC, 0, sv) != 0)
        throw IoError(fmt::format("socketpair for a hemicube worker failed: {}", std::strerror(errno)));
    std::fflush(nullptr);
    pid_ = ::fork();
    if (pid_ < 0) {
        const int err = errno;
        ::close(sv[0]);
        ::close(sv[1]);
        throw IoError(fmt::format("fork of a hemicube worker failed: {}", std::strerror(err)));
    }
    if (pid_ == 0) {
        // Keep only stdio and this child's socket (as fd 3): the parent's ends of earlier
        // siblings' sockets must not stay open here, or those siblings never see the end of
        // their requests.
        int fd = sv[1];
        if (fd != 3) {
            ::dup2(fd, 3);
            fd = 3;
        }
        ::close_range(4, ~0u, 0);
        setenv("LP_NUM_THREADS", "0", 0);
        child_main(fd, scene, pieces, layout, opt);
    }
    ::close(sv[1]);
    fd_ = sv[0];
}

void ProcessEngine::hang_up() {
    if (fd_ >= 0) ::close(fd_);  // the child sees the end of its requests and exits
    fd_ = -1;
}

ProcessEngine::~ProcessEngine() {
    hang_up();
    if (pid_ > 0) {
        int status = 0;
        while (::waitpid(pid_, &status, 0) < 0 && errno == EINTR) {
        }
    }
}

std::pair<std::string, std::string> ProcessEngine::hello() {
    Reply r{};
    recv_or_throw(&r, sizeof r);
    std::string text = read_text(r.count);
    if (r.error) throw_error(static_cast<ErrorKind>(r.error), text);
    const auto nl = text.find('\n');
    return {text.substr(0, nl), nl == std::string::npos ? std::string() : text.substr(nl + 1)};
}

void ProcessEngine::row(std::uint32_t p, std::span<const Vec3> points, std::span<const double> weights, SparseRow& out,
                        HemicubeStats& st) {
    submit(p, points, weights);
    collect(out, st);
}

// The child serves requests in the order sent, so replies come back in that order: collect reads
// the oldest row's. A sampled row's points go with it in the same message.
void ProcessEngine::submit(std::uint32_t p, std::span<const Vec3> points, std::span<const double> weights) {
    FFCUBE_CHECK_MSG(points.size() == weights.size(), "ProcessEngine::submit: one weight per sender point");
    if (points.empty()) {
        const RequestMsg req{Request::Row, p};
        send_or_throw(&req, sizeof req);
        return;
    }
    RequestMsg req{Request::SampledRow, p};
    std::uint64_t m = points.size();
    std::array<iovec, 4> parts{{{&req, sizeof req},
                                {&m, sizeof m},
                                {const_cast<Vec3*>(points.data()), m * sizeof(Vec3)},
                                {const_cast<double*>(weights.data()), m * sizeof(double)}}};
    try {
        send_parts(fd_, parts);
    } catch (const PeerGone&) {
        child_gone();
    }
}

void ProcessEngine::collect(SparseRow& out, HemicubeStats& st) {
    const Reply r = read_reply();
    out.col.resize(r.count);
    out.val.resize(r.count);
    if (r.count) {
        recv_or_throw(out.col.data(), r.count * sizeof(std::uint32_t));
        recv_or_throw(out.val.data(), r.count * sizeof(double));
    }
    stats::merge(st, stats::from_words<HemicubeStats>(r.counts));
}

void ProcessEngine::item_buffer(std::uint32_t p, std::vector<std::uint32_t>& out) {
    const Reply r = request(static_cast<std::uint32_t>(Request::ItemBuffer), p);
    out.resize(r.count);
    if (r.count) recv_or_throw(out.data(), r.count * sizeof(std::uint32_t));
}

void ProcessEngine::send_scene(std::span<const std::uint8_t> blob) {
    const RequestMsg req{Request::SetScene, 0};
    const std::uint64_t n = blob.size();
    send_or_throw(&req, sizeof req);
    send_or_throw(&n, sizeof n);
    if (n) send_or_throw(blob.data(), n);
}

void ProcessEngine::await_scene() { read_reply(); }

void ProcessEngine::set_scene(const Scene& scene, const ScenePieces&) {
    send_scene(serialize_scene(scene));
    await_scene();
}

ProcessEngine::Reply ProcessEngine::request(std::uint32_t kind, std::uint32_t p) {
    const RequestMsg req{static_cast<Request>(kind), p};
    send_or_throw(&req, sizeof req);
    return read_reply();
}

// The next reply's header; a reply that carries the child's error is thrown as its class.
ProcessEngine::Reply ProcessEngine::read_reply() {
    Reply r{};
    recv_or_throw(&r, sizeof r);
    if (r.error) throw_error(static_cast<ErrorKind>(r.error), read_text(r.count));
    return r;
}

// A closed socket while sending is the child gone as much as while reading (rows are pipelined:
// the next row is sent before the last one's reply is read, so a child that died on that row is
// often seen here first), and is reported the same way: how it ended.
void ProcessEngine::send_or_throw(const void* data, std::size_t size) {
    try {
        send_all(fd_, data, size);
    } catch (const PeerGone&) {
        child_gone();
    }
}

std::string ProcessEngine::read_text(std::uint64_t n) {
    std::string text(n, '\0');
    if (n) recv_or_throw(text.data(), n);
    return text;
}

void ProcessEngine::recv_or_throw(void* data, std::size_t size) {
    bool got = false;
    try {
        got = recv_all(fd_, data, size);
    } catch (const PeerGone&) {  // reset (the child ended with a request of ours unread), or cut short
    }
    if (!got) child_gone();
}

// The child's end of the socket is closed: it has ended or is ending. Waits for it and says how.
void ProcessEngine::child_gone() {
    int status = 0;
    std::string how = "exited";
    if (pid_ > 0 && ::waitpid(pid_, &status, 0) == pid_) {
        how = WIFSIGNALED(status) ? fmt::format("was killed by signal {}", WTERMSIG(status))
                                  : fmt::format("exited with status {}", WEXITSTATUS(status));
        pid_ = -1;
    }
    throw IoError("a hemicube worker process " + how + " unexpectedly");
}

}  // namespace ffcube
