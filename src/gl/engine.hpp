// How a hemicube worker thread computes: through an Engine, either in this process on a GL
// context of its own (LocalEngine, hemicube_worker.hpp) or in a child process that owns the
// context (ProcessEngine, process_engine.hpp). Another transport (MPI ranks) is one more Engine.
#pragma once

#include <cstdint>
#include <span>
#include <vector>

#include "ffcube/formfactor/sparse.hpp"
#include "ffcube/gl/hemicube_provider.hpp"
#include "ffcube/hemicube/pieces.hpp"
#include "ffcube/scene/scene.hpp"

namespace ffcube {

class Engine {
public:
    virtual ~Engine() = default;
    virtual void start() = 0;  // on the worker thread, before the first request
    // The measure contract: row p into out, from these sender points with these weights (the
    // weighted sum of sub-hemicubes at half the resolution, each point with its own visibility)
    // or, with no points, from one hemicube at the centroid at the full resolution; the work
    // done is added to st. Which points is the caller's rule (accuracy's plan). Errors are thrown
    // as the class they were raised as, wherever that was (core/error.hpp).
    virtual void row(std::uint32_t p, std::span<const Vec3> points, std::span<const double> weights, SparseRow& out,
                     HemicubeStats& st) = 0;
    // row() in two halves, for engines that compute elsewhere (pipelined() true): submit asks for
    // row p and returns at once; collect waits for the oldest row submitted and not collected.
    // The thread can then plan and send the next row, and finish the last one, while the engine
    // computes (HemicubeRowProvider keeps one row waiting at each worker process).
    virtual bool pipelined() const { return false; }
    virtual void submit(std::uint32_t p, std::span<const Vec3> points, std::span<const double> weights);
    virtual void collect(SparseRow& out, HemicubeStats& st);
    virtual void item_buffer(std::uint32_t p, std::vector<std::uint32_t>& out) = 0;
    virtual void stop() = 0;  // on the worker thread, after the last request
    // Draw `scene` (cut into `pieces`) from the next request on; from the provider's thread,
    // between runs. Both must outlive the engine or the next call.
    virtual void set_scene(const Scene& scene, const ScenePieces& pieces) = 0;
    // Tells the engine to wind down before it is destroyed (a worker process: its socket closed,
    // so it exits while the other engines are told too); nothing may be asked of it after.
    virtual void hang_up() {}
};

}  // namespace ffcube
