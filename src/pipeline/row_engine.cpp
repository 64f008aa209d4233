#include "ffcube/pipeline/row_engine.hpp"

#include <algorithm>

#include "ffcube/core/error.hpp"
#include "ffcube/raycast/raycast_provider.hpp"

namespace ffcube {

bool rays_preferred(std::size_t pieces, std::size_t patches) {
    return pieces >= kFineRowsByRaysMinPieces ||
           (pieces >= kRaysMinMeshPieces && patches <= kRaysMaxPatchesPerPiece * pieces);
}

std::uint64_t default_fine_row_rays(int resolution) {
    const auto n = static_cast<std::uint64_t>(resolution > 0 ? resolution : 0);
    return std::max(n * n / 2, std::min<std::uint64_t>(2 * n * n, 32768));
}

SceneFacts scene_facts(const Scene& drawn, int resolution, const CostModel& costs) {
    SceneFacts f;
    f.costs = costs;
    f.pieces = drawn.grids.size();
    f.patches = drawn.patches.size();
    f.obstructions = drawn.obstruction_first < drawn.patches.size();
    f.resolution = resolution;
    return f;
}

unsigned hemicubes_for_plan(RowProvider::RowPlan plan) {
    switch (plan) {
        case RowProvider::RowPlan::centre: return 1;
        case RowProvider::RowPlan::sampled: return 4;
        case RowProvider::RowPlan::sampled_fine: return 16;
        case RowProvider::RowPlan::skip: break;
    }
    return 0;
}

double hemicube_row_ns(const CostModel& m, RowProvider::RowPlan plan, int resolution, std::size_t pieces) {
    const double n = resolution;
    return hemicubes_for_plan(plan) * (3.0 * n * n * m.pixel_ns + static_cast<double>(pieces) * m.piece_ns);
}

double ray_row_ns(const CostModel& m, std::uint64_t rays) { return static_cast<double>(rays) * m.ray_ns; }

std::uint64_t expected_row_rays(double tolerance, std::uint64_t fixed_rays) {
    return tolerance > 0 ? tolerance_rays(tolerance).most : fixed_rays;
}

MethodCosts scene_method_costs(const SceneFacts& scene, std::uint64_t rays) {
    MethodCosts c;
    const bool one_patch_a_piece = scene.patches <= kRaysMaxPatchesPerPiece * scene.pieces;
    const auto plan = one_patch_a_piece ? RowProvider::RowPlan::sampled_fine : RowProvider::RowPlan::centre;
    c.hemicubes = hemicubes_for_plan(plan);
    c.hemicube_ns = hemicube_row_ns(scene.costs, plan, scene.resolution, scene.pieces);
    c.rays_ns = ray_row_ns(scene.costs, rays);
    return c;
}

EngineChoice engine_for_row(FineRows fine_rows, std::uint64_t fine_row_rays, const SceneFacts& scene,
                            RowProvider::RowPlan plan) {
    if (fine_rows == FineRows::rays && scene.obstructions)
        throw InputError("--fine-rows rays: the scene has obstruction-only surfaces, which the ray caster "
                         "credits on either side (use --fine-rows hemicubes or auto)");
    if (plan != RowProvider::RowPlan::sampled_fine) return {};
    const std::uint64_t rays = fine_row_rays ? fine_row_rays : default_fine_row_rays(scene.resolution);
    const auto cheaper = [&] {
        if (scene.costs.builtin()) return rays_preferred(scene.pieces, scene.patches);
        return ray_row_ns(scene.costs, rays) < hemicube_row_ns(scene.costs, plan, scene.resolution, scene.pieces);
    };
    const bool by_rays =
        fine_rows == FineRows::rays || (fine_rows == FineRows::automatic && !scene.obstructions && cheaper());
    if (!by_rays) return {};
    return {RowProvider::RowEngine::rays, rays};
}

RowDriver::RowDriver(const Scene& drawn, HemicubeRowProvider& hemicube, FineRows fine_rows, std::uint64_t fine_row_rays,
                     std::uint64_t seed, const CostModel& costs)
    : scene_(drawn),
      hemicube_(hemicube),
      fine_rows_(fine_rows),
      fine_row_rays_(fine_row_rays),
      facts_(scene_facts(drawn, hemicube.resolution(), costs)),
      fine_(engine_for_row(fine_rows, fine_row_rays, facts_, RowPlan::sampled_fine)),  // throws a bad choice now
      seed_(seed) {}

RowDriver::~RowDriver() = default;

void RowDriver::compute_rows_staged(std::span<const std::uint32_t> rows, const RowStages& stages, const RowSink& sink) {
    if (!stages.plan) {
        hemicube_.compute_rows_staged(rows, stages, sink);
        return;
    }
    RowStages driven = stages;
    driven.plan = [&](std::size_t k, std::uint32_t i, RowRequest& request) {
        stages.plan(k, i, request);
        request.engine = engine_for_row(fine_rows_, fine_row_rays_, facts_, request.plan).engine;
    };
    driven.cast = [this](unsigned worker, std::uint32_t i, SparseRow& out) { cast(worker, i, out); };
    hemicube_.compute_rows_staged(rows, driven, sink);
}

void RowDriver::cast(unsigned worker, std::uint32_t i, SparseRow& out) {
    const RaycastRowProvider* c = nullptr;
    {
        const std::lock_guard lock(caster_mutex_);
        if (!caster_) {
            RaycastOptions ro;
            ro.rays = fine_.rays;
            ro.threads = 1;
            ro.seed = seed_;
            caster_ = std::make_unique<RaycastRowProvider>(scene_, ro);
            scratch_.resize(hemicube_.threads());
        }
        c = caster_.get();
    }
    FFCUBE_CHECK_MSG(worker < scratch_.size(), "RowDriver::cast: a worker beyond the hemicube's threads");
    c->cast_row(i, out, scratch_[worker]);
}

}  // namespace ffcube
