// Hemicube workers as child processes: fork, then requests and replies over a Unix socket pair.
//
// Why processes: Mesa's llvmpipe rasterizes every context of a process through one screen, under
// one lock, so two contexts on two threads run at about 1.1× one (measured, docs/benchmarks.md);
// two processes run at 2×. Children are forked before this process has made any GL context and
// while it runs a single thread, so they inherit the scene (copy-on-write) and no locks or GL
// state; otherwise the provider falls back to threads (LocalEngine).
//
// Errors: an exception in the child comes back as its class tag (core/error.hpp ErrorKind) and
// message and is thrown again as that class here. Socket, fork and pipe failures, and a child
// that dies, are IoError.
#pragma once

#include <cstdint>
#include <span>
#include <string>
#include <sys/types.h>
#include <utility>

#include "ffcube/hemicube/layout.hpp"
#include "ffcube/hemicube/pieces.hpp"
#include "gl/engine.hpp"

namespace ffcube {

// True when fork() is safe here: this process runs a single thread (no lock can be held by a
// thread the child would not have) and has never made a GL context (no driver state to share).
bool can_fork_workers();

class ProcessEngine final : public Engine {
public:
    // Forks the child, which makes its own GL context and a Worker; call only while
    // can_fork_workers(). Everything referenced is the child's copy-on-write from then on.
    ProcessEngine(const Scene& scene, const ScenePieces& pieces, const HemicubeLayout& layout, const HemicubeOptions& opt);
    ~ProcessEngine() override;  // closes the socket (the child then exits) and reaps the child
    void hang_up() override;    // closes the socket now: the child exits while others are told
    // Reads the child's hello: its backend and GL_RENDERER, or throws why it could not start.
    std::pair<std::string, std::string> hello();
    void start() override {}
    void stop() override {}
    void row(std::uint32_t p, std::span<const Vec3> points, std::span<const double> weights, SparseRow& out,
             HemicubeStats& st) override;
    bool pipelined() const override { return true; }
    void submit(std::uint32_t p, std::span<const Vec3> points, std::span<const double> weights) override;
    void collect(SparseRow& out, HemicubeStats& st) override;
    void item_buffer(std::uint32_t p, std::vector<std::uint32_t>& out) override;
    // Sends the scene and waits for the child to rebuild its pieces and Worker (a child keeps
    // its GL context across scenes). `pieces` is not sent: the child prepares its own.
    void set_scene(const Scene& scene, const ScenePieces& pieces) override;
    // The same in two halves, so that the children of one provider rebuild at the same time:
    // send_scene with the serialized scene (scene/scene_blob.hpp), then await_scene for the reply.
    void send_scene(std::span<const std::uint8_t> blob);
    void await_scene();

    struct Reply;  // the wire format's reply header (process_engine.cpp)

private:
    Reply request(std::uint32_t kind, std::uint32_t p);
    std::string read_text(std::uint64_t n);
    Reply read_reply();
    void send_or_throw(const void* data, std::size_t size);
    void recv_or_throw(void* data, std::size_t size);
    [[noreturn]] void child_gone();  // the socket's other end is closed: how the child ended

    int fd_ = -1;
    pid_t pid_ = -1;
};

}  // namespace ffcube
