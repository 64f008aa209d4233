// The public face of the hemicube engine: it prepares the scene's pieces (hemicube/pieces.hpp),
// starts one Engine per worker (a forked process, process_engine.hpp, or a GL context on a
// thread, hemicube_worker.hpp) and hands rows out through an OrderedRowPool
// (formfactor/ordered_pool.hpp), which delivers them in the order asked.
#include "ffcube/gl/hemicube_provider.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <exception>
#include <mutex>
#include <thread>
#include <tuple>

#include "ffcube/core/error.hpp"
#include "ffcube/core/stats.hpp"
#include "ffcube/core/timer.hpp"
#include "ffcube/formfactor/ordered_pool.hpp"
#include "ffcube/hemicube/layout.hpp"
#include "ffcube/hemicube/pieces.hpp"
#include "ffcube/geometry/quadrature.hpp"
#include "ffcube/scene/scene_blob.hpp"
#include "gl/engine.hpp"
#include "gl/hemicube_worker.hpp"
#include "gl/process_engine.hpp"

namespace ffcube {

void Engine::submit(std::uint32_t, std::span<const Vec3>, std::span<const double>) { FFCUBE_CHECK_MSG(false, "Engine::submit on an engine that is not pipelined"); }
void Engine::collect(SparseRow&, HemicubeStats&) {
    FFCUBE_CHECK_MSG(false, "Engine::collect on an engine that is not pipelined");
}

// Engines live as long as the provider; the pool's threads (one per engine) are stopped before
// the engines (contexts, child processes) go.
struct HemicubeRowProvider::Impl {
    const Scene* scene;  // set_scene replaces it (and the pieces, in place)
    HemicubeOptions opt;
    HemicubeLayout layout;
    ScenePieces pieces;
    std::string backend, renderer;
    bool processes = false;
    std::vector<std::unique_ptr<Engine>> engines;
    std::unique_ptr<OrderedRowPool> pool;  // after engines: destroyed first
    mutable std::mutex stats_mutex;
    HemicubeStats stats;
    Impl(const Scene& s, const HemicubeOptions& o) : scene(&s), opt(o), layout(o.resolution), pieces(prepare_pieces(s.grids)) {}
    ~Impl() {
        pool.reset();
        // Every worker process told at once, then each reaped (as the engines go): they wind
        // down side by side, not one after the other.
        for (auto& e : engines) e->hang_up();
    }

    // A sampled request without points: the engine's own rule, the patch's quadrature points
    // (2 or 4 per axis: sampled or sampled_fine), into `scratch`. Returns the points to send.
    std::pair<std::span<const Vec3>, std::span<const double>> sender_points(std::uint32_t i, const RowProvider::RowRequest& r,
                                                                            RowProvider::RowRequest& scratch) const {
        using RowPlan = RowProvider::RowPlan;
        if (!r.sampled()) return {};
        if (!r.points.empty() || r.partly_enclosed) return {r.points, r.weights};
        const auto v = scene->patch_vertices(i);
        patch_quadrature(std::span<const Vec3>(v.data(), scene->patches[i].count), r.plan == RowPlan::sampled_fine ? 4 : 2,
                         scratch.points, scratch.weights);
        return {scratch.points, scratch.weights};
    }

    // Rows through the pool; 'given' (compute_rows_requested's, or empty: every row centre) says
    // how to measure each row, unless the stages (compute_rows_staged's) plan and finish them.
    // A request for the ray caster (RowEngine::rays, the driver's choice) is measured by the
    // stages' cast on the pool thread; every other row by the thread's engine.
    void run(std::span<const std::uint32_t> rows, std::span<const RowProvider::RowRequest> given,
             const RowProvider::RowStages* stages, const RowSink& sink) {
        using RowPlan = RowProvider::RowPlan;
        using RowEngine = RowProvider::RowEngine;
        using RowRequest = RowProvider::RowRequest;
        const bool planned = stages && stages->plan;
        // One request being planned per pool thread (its vectors' capacity kept from row to row),
        // and one for the default quadrature points.
        std::vector<RowRequest> own(planned ? engines.size() : 0), quadrature(engines.size());
        const auto plan_of = [&](unsigned w, std::size_t k, std::uint32_t i) -> const RowRequest& {
            if (!planned) {
                static const RowRequest centre;
                return given.empty() ? centre : given[k];
            }
            RowRequest& r = own[w];
            r.reset();
            stages->plan(k, i, r);
            FFCUBE_CHECK_MSG(r.engine == RowEngine::provider || stages->cast,
                             "HemicubeRowProvider: a row for the ray caster, and no ray caster");
            return r;
        };
        // The row measured by the other engine (stages->cast) on pool thread w; returns its seconds.
        const auto cast = [&](unsigned w, std::uint32_t i, SparseRow& out) {
            Stopwatch watch;
            stages->cast(w, i, out);
            return watch.seconds();
        };
        // What a request counts before its row is measured.
        const auto count = [](const RowRequest& r, HemicubeStats& local) {
            if (r.plan == RowPlan::skip) {
                ++local.skipped_rows;
            } else if (r.engine == RowEngine::rays) {
                local.fine_rows_cast = 1;
            } else if (r.plan != RowPlan::centre) {
                ++local.sampled_rows;
                if (r.partly_enclosed) ++local.partly_enclosed_rows;
            }
        };
        const auto finish = [&](std::size_t k, std::uint32_t i, SparseRow& out, const HemicubeStats& local) {
            {
                // Merged before the row is handed on: the sink sees stats that include its row.
                std::lock_guard lock(stats_mutex);
                stats::merge(stats, local);
            }
            if (stages && stages->finish) stages->finish(k, i, out);
        };
        if (engines.front()->pipelined()) {
            // Worker processes: row k + 1 is planned and sent before row k's reply is read, so the
            // child starts it as soon as it has sent row k, and this thread plans and finishes
            // rows (the correction's analysis, exact values and sender quadrature) while the
            // child draws. What a row in flight needs at its collection waits here, one slot per
            // listed row. A row for the ray caster is cast when it is planned, while the child
            // draws the row before it, and kept until its turn to be collected.
            std::vector<HemicubeStats> counted(rows.size());
            std::vector<std::uint8_t> sent(rows.size());
            std::vector<SparseRow> cast_rows(stages && stages->cast ? rows.size() : 0);
            const OrderedRowPool::Submit submit = [&](unsigned w, std::size_t k, std::uint32_t i) {
                const RowRequest& r = plan_of(w, k, i);
                count(r, counted[k]);
                if (r.empty()) return;
                if (r.engine == RowEngine::rays) {
                    counted[k].cast_seconds = cast(w, i, cast_rows[k]);
                    return;
                }
                const auto [points, weights] = sender_points(i, r, quadrature[w]);
                engines[w]->submit(i, points, weights);
                sent[k] = 1;
            };
            const OrderedRowPool::Compute collect = [&](unsigned w, std::size_t k, std::uint32_t i, SparseRow& out) {
                HemicubeStats& local = counted[k];
                if (sent[k]) {
                    engines[w]->collect(out, local);
                } else if (local.fine_rows_cast) {
                    out = std::move(cast_rows[k]);
                    cast_rows[k] = SparseRow{};  // its storage goes with the row
                } else {
                    out.clear();  // skipped, or no part of the sender exposed
                }
                finish(k, i, out, local);
            };
            pool->run_pipelined(rows, submit, collect, sink);
            return;
        }
        const OrderedRowPool::Compute compute = [&](unsigned w, std::size_t k, std::uint32_t i, SparseRow& out) {
            HemicubeStats local;
            const RowRequest& r = plan_of(w, k, i);
            count(r, local);
            if (r.empty()) {
                out.clear();
            } else if (r.engine == RowEngine::rays) {
                local.cast_seconds = cast(w, i, out);
            } else {
                const auto [points, weights] = sender_points(i, r, quadrature[w]);
                engines[w]->row(i, points, weights, out, local);
            }
            finish(k, i, out, local);
        };
        pool->run(rows, compute, sink);
    }
};

HemicubeRowProvider::HemicubeRowProvider(const Scene& scene, const HemicubeOptions& options) {
    check_row_resolution(options.resolution);
    if (scene.patches.size() >= kBackFace - 1) throw InputError("the scene has too many patches for 32-bit item IDs");
    unsigned n = options.threads ? options.threads : std::max(1u, std::thread::hardware_concurrency());
    n = static_cast<unsigned>(std::min<std::size_t>(n, std::max<std::size_t>(1, scene.patches.size())));
    impl_ = std::make_unique<Impl>(scene, options);
    Impl& im = *impl_;
    im.opt.threads = n;
    // llvmpipe starts rasterizer threads (one per core) for every context unless told otherwise;
    // K workers would then run K × cores threads that fight over the cores. With one rasterizing
    // thread per context, --threads K uses K cores, and scaling is the workers' (measured in
    // docs/benchmarks.md). A user's own LP_NUM_THREADS is respected. Must precede the first
    // context: llvmpipe reads it when its screen is created.
    setenv("LP_NUM_THREADS", "0", /*overwrite=*/0);
    if (im.opt.worker_processes && can_fork_workers()) {
        im.processes = true;
        // Every child is forked before any is awaited: each makes its GL context and compiles
        // its programs (a tenth of a second or more on llvmpipe) at the same time as the others.
        for (unsigned t = 0; t < n; ++t)
            im.engines.push_back(std::make_unique<ProcessEngine>(*im.scene, im.pieces, im.layout, im.opt));
        for (auto& e : im.engines)  // throws why a child could not start
            std::tie(im.backend, im.renderer) = static_cast<ProcessEngine&>(*e).hello();
    } else {
        std::unique_ptr<GlContext> first = create_headless_context(options.backend);
        im.backend = first->backend();
        im.renderer = first->renderer();
        std::vector<std::unique_ptr<GlContext>> contexts;
        for (unsigned t = 1; t < n; ++t) contexts.push_back(first->create_sibling());
        im.engines.push_back(std::make_unique<LocalEngine>(std::move(first), *im.scene, im.pieces, im.layout, im.opt));
        for (auto& c : contexts)
            im.engines.push_back(std::make_unique<LocalEngine>(std::move(c), *im.scene, im.pieces, im.layout, im.opt));
    }
    im.pool = std::make_unique<OrderedRowPool>(
        n, [&im](unsigned w) { im.engines[w]->start(); }, [&im](unsigned w) { im.engines[w]->stop(); });
}

HemicubeRowProvider::~HemicubeRowProvider() = default;

std::uint32_t HemicubeRowProvider::size() const { return static_cast<std::uint32_t>(impl_->scene->patches.size()); }

void HemicubeRowProvider::compute_rows(std::span<const std::uint32_t> rows, const RowSink& sink) {
    for (std::uint32_t i : rows) FFCUBE_CHECK_MSG(i < size(), "row index out of range");
    impl_->run(rows, {}, nullptr, sink);
}

void HemicubeRowProvider::compute_rows_requested(std::span<const std::uint32_t> rows,
                                                 std::span<const RowRequest> requests, const RowSink& sink) {
    for (std::uint32_t i : rows) FFCUBE_CHECK_MSG(i < size(), "row index out of range");
    FFCUBE_CHECK_MSG(requests.size() == rows.size(), "compute_rows_requested: one request per row");
    for (const RowRequest& r : requests)
        FFCUBE_CHECK_MSG(r.engine == RowEngine::provider, "compute_rows_requested: a row for the ray caster");
    impl_->run(rows, requests, nullptr, sink);
}

void HemicubeRowProvider::compute_rows_staged(std::span<const std::uint32_t> rows, const RowStages& stages,
                                              const RowSink& sink) {
    for (std::uint32_t i : rows) FFCUBE_CHECK_MSG(i < size(), "row index out of range");
    impl_->run(rows, {}, &stages, sink);
}

std::vector<std::uint32_t> HemicubeRowProvider::item_buffer(std::uint32_t i) {
    FFCUBE_CHECK_MSG(i < size(), "patch index out of range");
    std::vector<std::uint32_t> result;
    Engine& first = *impl_->engines[0];
    impl_->pool->run_on_first([&] { first.item_buffer(i, result); });
    return result;
}

void HemicubeRowProvider::set_scene(const Scene& scene) {
    if (scene.patches.size() >= kBackFace - 1) throw InputError("the scene has too many patches for 32-bit item IDs");
    Impl& im = *impl_;
    im.scene = &scene;
    im.pieces = prepare_pieces(scene.grids);  // in place: the engines hold its address
    if (im.processes) {
        // Every child takes the scene at once; then each reply is awaited (all of them, so that
        // none is left mid-message when one fails).
        const std::vector<std::uint8_t> blob = serialize_scene(scene);
        for (auto& e : im.engines) static_cast<ProcessEngine&>(*e).send_scene(blob);
        std::exception_ptr first;
        for (auto& e : im.engines) {
            try {
                static_cast<ProcessEngine&>(*e).await_scene();
            } catch (...) {
                if (!first) first = std::current_exception();
            }
        }
        if (first) std::rethrow_exception(first);
    } else {
        for (auto& e : im.engines) e->set_scene(scene, im.pieces);
    }
    std::lock_guard lock(im.stats_mutex);
    im.stats = HemicubeStats{};
}

HemicubeStats HemicubeRowProvider::stats() const {
    std::lock_guard lock(impl_->stats_mutex);
    return impl_->stats;
}

void HemicubeRowProvider::merge_stats(const HemicubeStats& other) {
    std::lock_guard lock(impl_->stats_mutex);
    stats::merge(impl_->stats, other);
}
std::string HemicubeRowProvider::backend() const { return impl_->backend; }
std::string HemicubeRowProvider::renderer() const { return impl_->renderer; }
unsigned HemicubeRowProvider::threads() const { return impl_->pool->size(); }
std::size_t HemicubeRowProvider::enclosure_planes() const {
    return impl_->opt.enclosure_without_depth ? impl_->pieces.enclosure.planes.size() : 0;
}
std::size_t HemicubeRowProvider::enclosure_pieces() const {
    const auto& e = impl_->pieces.enclosure.piece;
    return impl_->opt.enclosure_without_depth ? static_cast<std::size_t>(std::count(e.begin(), e.end(), 1)) : 0;
}
std::string HemicubeRowProvider::workers() const { return impl_->processes ? "processes" : "threads"; }

int HemicubeRowProvider::resolution() const { return impl_->layout.resolution(); }

}  // namespace ffcube
