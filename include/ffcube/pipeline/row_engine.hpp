// The driver's one per-row decision: which engine measures a row, the GL hemicubes or the ray
// caster (docs/architecture.md, "One row, from request to sink": request → plan → measure →
// correct → sinks). The plan (accuracy) says how a row is to be measured (centre, 2 × 2 or
// 4 × 4 sender points, or not at all); engine_for_row says by which engine, from the scene's
// facts and the plan alone; RowDriver hands the row to it on the hemicube provider's worker
// thread. Rows planned at 4 × 4 (an occluder touches the sender) are ray-cast where a ray-cast
// row costs less than the sixteen sub-hemicubes (row costs below), or, with the built-in cost
// model, where rays_preferred (docs/accuracy.md, "Rows an occluder touches, by rays", "Cost model").
#pragma once

#include <cstddef>
#include <cstdint>
#include <memory>
#include <mutex>
#include <span>
#include <vector>

#include "ffcube/formfactor/row_provider.hpp"
#include "ffcube/gl/hemicube_provider.hpp"
#include "ffcube/pipeline/cost_model.hpp"
#include "ffcube/raycast/raycast_provider.hpp"
#include "ffcube/scene/scene.hpp"

namespace ffcube {

// --fine-rows: how rows planned at 4 × 4 sub-hemicubes (RowPlan::sampled_fine) are measured.
// hemicubes: drawn; rays: cast from the whole sender with fine_row_rays rays (an InputError on a
// scene with obstruction-only surfaces: the ray caster credits either side of them, hemicubes
// the facing one); automatic: rays where rays_preferred and the scene has no obstruction-only
// surfaces, else hemicubes.
enum class FineRows { hemicubes, rays, automatic };

// A mesh of kFineRowsByRaysMinPieces pieces or more, or of kRaysMinMeshPieces with at most
// kRaysMaxPatchesPerPiece patches a piece on average (one patch a facet, as --no-subdivide
// makes): there the rays cost no more than the 16 sub-hemicubes on llvmpipe and are the more
// accurate. On cities of 100, 300 and 600 facets the rays were faster and about twice as
// accurate, and the drawn 4 × 4 rows biased towards sky (a wall standing on the sender is a
// near-singular integrand that sixteen points miss); a scene of few pieces and many patches (the
// Cornell box, 170 a piece) keeps hemicubes, whose rows there are the more accurate
// (docs/benchmarks.md, "Rays in coherent packets, and --method auto"). --method auto casts every
// row on such a mesh (resolve_row_method). This is the built-in cost model's rule; a --cost-model
// file's costs replace it (scene_method_costs, engine_for_row).
inline constexpr std::size_t kFineRowsByRaysMinPieces = 1000;
inline constexpr std::size_t kRaysMinMeshPieces = 100;
inline constexpr std::size_t kRaysMaxPatchesPerPiece = 4;
bool rays_preferred(std::size_t pieces, std::size_t patches);

// --fine-row-rays' default at resolution N: max(N²/2, min(2 N², 32,768)): 32,768 at N = 128 and
// 256. Half the count of the padded stratified sampler it replaced: the scrambled Sobol' rays
// (raycast/sampling.hpp) are as accurate at half the rays (the 22,881-facet city: row L2 error
// 1.43e-3 at 32,768 against 1.46e-3 at 65,536 before; docs/benchmarks.md).
std::uint64_t default_fine_row_rays(int resolution);

// What the choice needs to know of the scene.
struct SceneFacts {
    std::size_t pieces = 0;    // the mesher's pieces (Scene::grids), what the hemicube draws
    std::size_t patches = 0;   // rows
    bool obstructions = false; // obstruction-only surfaces (Scene::obstruction_first)
    int resolution = 256;      // the hemicube's
    CostModel costs;           // --cost-model (built-in: the piece-count rule decides)
};
SceneFacts scene_facts(const Scene& drawn, int resolution, const CostModel& costs = {});

// What a row costs by each engine, in nanoseconds of one worker, priced by a cost model
// (`ffcube calibrate`, pipeline/cost_model.hpp). Nothing is timed: the same model, the same costs.
// - A hemicube row planned `plan` draws hemicubes_for_plan(plan) hemicubes (centre 1, 2 × 2
//   sub-hemicubes 4, 4 × 4 16, skip 0: a row every pair of which is analytic draws nothing),
//   each 3N² pixels and every piece: hemicubes × (3N² × pixel_ns + pieces × piece_ns).
// - A ray-cast row casts `rays` rays: rays × ray_ns. Refined to a tolerance E, its count is
//   expected_row_rays(E, …): the budget of tolerance_rays(E), 2^⌈log2(64/E)⌉ (65,536 at
//   E = 1e-3), which a city's rows spend nearly whole (63,409 of 65,536 a row on the
//   22,881-facet city; docs/benchmarks.md, "Accuracy by target"); without one, the fixed count.
unsigned hemicubes_for_plan(RowProvider::RowPlan plan);
double hemicube_row_ns(const CostModel& m, RowProvider::RowPlan plan, int resolution, std::size_t pieces);
double ray_row_ns(const CostModel& m, std::uint64_t rays);
std::uint64_t expected_row_rays(double tolerance, std::uint64_t fixed_rays);

// --method auto's whole-scene choice, by costs: a scene's rows are measured by rays where a
// ray-cast row costs less than the hemicube row its rows are typically planned as. A mesh of at
// most kRaysMaxPatchesPerPiece patches a piece (one patch a facet, or nearly) has nearly every row
// planned at 4 × 4 (an occluder touches every facet: 1,491 of 1,500, 4,058 of 5,000 and 18,813 of
// 22,881 rows on generated cities), so its row is costed as 16 hemicubes; a subdivided mesh's rows
// mostly lie inside their piece, touch no occluder and are drawn once (centre). Each row class is
// then measured by the cheaper engine the driver can give it (engine_for_row): in a hemicube run
// the 4 × 4 rows by costs, the centre and 2 × 2 rows drawn (the correction's estimate of a row
// cast instead is the 4 × 4 class's only).
struct MethodCosts {
    double hemicube_ns = 0;  // the typical row of this mesh by hemicubes
    double rays_ns = 0;      // a row by rays, `rays` of them
    unsigned hemicubes = 1;  // hemicubes in the typical row (1 or 16)
    bool rays_cheaper() const { return rays_ns < hemicube_ns; }
};
MethodCosts scene_method_costs(const SceneFacts& scene, std::uint64_t rays);

struct EngineChoice {
    RowProvider::RowEngine engine = RowProvider::RowEngine::provider;
    std::uint64_t rays = 0;  // rays per row when engine is rays
};
// The engine of a row planned `plan`, given --fine-rows and --fine-row-rays (0: the default for
// the resolution). With FineRows::automatic a row planned at 4 × 4 goes to rays where
// ray_row_ns(its rays) < hemicube_row_ns(sampled_fine) by scene.costs, or, with the built-in cost
// model, where rays_preferred (the rule the built-in costs cannot reproduce: it ignores N and the
// ray count, which any cost depends on; docs/accuracy.md, "Cost model"). Pure: the same
// arguments, the same choice. Throws InputError for FineRows::rays on a scene with
// obstruction-only surfaces.
EngineChoice engine_for_row(FineRows fine_rows, std::uint64_t fine_row_rays, const SceneFacts& scene,
                            RowProvider::RowPlan plan);

// The driver around the hemicube provider: its staged rows (accuracy's plan and correction
// around them) go through unchanged, but each row's request gets its engine (engine_for_row),
// and a row for the ray caster is cast through RowStages::cast on the hemicube's worker thread,
// by a ray caster on the same scene made at the first such row (its Embree scene: a fraction of
// a second on 23k triangles; made after the worker processes are forked), seeded by the
// hemicube's seed. Both providers and the scene must outlive it.
class RowDriver final : public RowProvider {
public:
    RowDriver(const Scene& drawn, HemicubeRowProvider& hemicube, FineRows fine_rows, std::uint64_t fine_row_rays,
              std::uint64_t seed, const CostModel& costs = {});
    ~RowDriver() override;
    std::uint32_t size() const override { return hemicube_.size(); }
    std::string name() const override { return hemicube_.name(); }
    void compute_rows(std::span<const std::uint32_t> rows, const RowSink& sink) override {
        hemicube_.compute_rows(rows, sink);
    }
    bool can_sample_sender() const override { return true; }
    std::uint64_t cast_fine_row_rays() const override { return fine_.engine == RowEngine::rays ? fine_.rays : 0; }
    void compute_rows_requested(std::span<const std::uint32_t> rows, std::span<const RowRequest> requests,
                                const RowSink& sink) override {
        hemicube_.compute_rows_requested(rows, requests, sink);
    }
    void compute_rows_staged(std::span<const std::uint32_t> rows, const RowStages& stages, const RowSink& sink) override;

    // Whether rows planned at 4 × 4 are ray-cast on this scene, and with how many rays each
    // (--fine-row-rays or its default, also when they are not).
    bool fine_rows_by_rays() const { return fine_.engine == RowEngine::rays; }
    std::uint64_t fine_row_rays() const {
        return fine_row_rays_ ? fine_row_rays_ : default_fine_row_rays(facts_.resolution);
    }
    const SceneFacts& facts() const { return facts_; }

private:
    void cast(unsigned worker, std::uint32_t i, SparseRow& out);

    const Scene& scene_;
    HemicubeRowProvider& hemicube_;
    FineRows fine_rows_;
    std::uint64_t fine_row_rays_;
    SceneFacts facts_;
    EngineChoice fine_;  // engine_for_row for a row planned sampled_fine
    std::uint64_t seed_;
    std::mutex caster_mutex_;
    std::unique_ptr<RaycastRowProvider> caster_;
    std::vector<RaycastRowProvider::RowScratch> scratch_;  // one per hemicube worker thread
};

}  // namespace ffcube
