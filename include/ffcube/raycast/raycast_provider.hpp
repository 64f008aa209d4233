// Rows of F by Monte Carlo ray casting through Embree 3: no GL at all, so it works where no
// context can be had, and it checks the hemicube on occluded scenes where no formula exists.
//
// Row i is estimated from `rays` rays leaving patch i: the first `rays` points of a 4-D Sobol'
// sequence, each dimension Owen-scrambled with seeds drawn from (seed, i) (raycast/sampling.hpp):
// two coordinates place the origin on the patch, two give a cosine-weighted direction about its
// front normal through the concentric map. Each ray's origin and direction are uniform on their
// own, so rows are unbiased for any number of rays. Hitting the front of patch j adds
// the ray's weight to F_ij; hitting a back face absorbs the ray (it blocks, and counts for
// nothing); a ray leaving the scene adds nothing. Weights: 1 on triangles and parallelograms,
// the bilinear map's Jacobian on other quads (area-uniform sampling), normalised so the weights
// of a row sum to 1. In a closed enclosure every ray hits a front face, so rows sum to 1 (to
// rounding).
//
// Statistics: each F_ij is a binomial fraction, standard error √(F(1−F)/rays) or less; the
// scrambled net lowers it well below (error about rays^−0.6 on a city's rows against rays^−0.5,
// a third of the binomial on a floor-to-wall factor at 4,096 rays: docs/accuracy.md, "The ray
// caster's sampling").
// Determinism: row i's random numbers come from (seed, i) alone, so rows do not depend on the
// number of threads or on which rows are asked for together.
#pragma once

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "ffcube/core/stats.hpp"
#include "ffcube/formfactor/row_provider.hpp"
#include "ffcube/scene/scene.hpp"

namespace ffcube {

struct RaycastOptions {
    std::uint64_t rays = 4096;  // rays per row (per patch), ≥ 1
    unsigned threads = 0;       // 0 = every core
    std::uint64_t seed = 0x5eed;
    // > 0: accuracy by target (docs/accuracy.md, "Accuracy by target"): `rays` is ignored; each
    // row is cast as kReplicates independently scrambled copies, doubled until the copies' spread
    // says the row's largest entry and its sum are within the tolerance, between
    // tolerance_rays(tolerance) rays. Rows then differ from the fixed-count rows.
    double tolerance = 0;
};

// Accuracy by target: the replicates of a row and Student's t for their mean (kReplicates − 1 =
// 7 degrees of freedom, two-sided 97.5%: 2.841). At two-sided 95% (2.365) 94.4% of a 1,000-facet
// city's rows had their true error within the estimate (docs/accuracy.md, "Accuracy by target"):
// the largest of a row's entries and its sum is a maximum over several spreads, so each needs a
// little more than 95%.
constexpr std::size_t kReplicates = 8;
constexpr double kReplicateT = 2.841;
// The least and the most rays of a row refined to tolerance E (powers of two): at least 3/E and
// 4,096 (with R rays, a share of the hemisphere that no ray hit is below 3/R at 95%: the rule of
// three; the estimate is never below it); at most 64/E (a ray weighs E/64), and 2^24. At 256/E a
// 22,881-facet city's default run (E = 1e-3) had spent more than 7 times the CPU of the old fixed
// 32,768 rays before it was stopped; at 64/E a row costs at most twice that count.
struct RayBudget {
    std::uint64_t least = 0, most = 0;
};
RayBudget tolerance_rays(double tolerance);

// The ray caster's statistics set (core/stats.hpp): rays traced (re-traces past a ray's own
// patch included, see the .cpp), rows refined to the tolerance, and of those the ones whose
// estimate was still above it when the budget was spent (the last two reported by the pipeline as
// rays_per_patch_mean and rows_at_ray_budget, with a tolerance only).
#define FFCUBE_RAYCAST_STATS(X)                                 \
    X(std::uint64_t, rays_traced, sum, "rays_traced")           \
    X(std::uint64_t, refined_rows, sum, "")                     \
    X(std::uint64_t, rows_at_budget, sum, "")
struct RaycastStats {
    FFCUBE_STATS(RaycastStats, FFCUBE_RAYCAST_STATS)
};

class RaycastRowProvider final : public RowProvider {
public:
    // Builds the Embree scene (one triangle mesh; quads as two triangles). Throws InputError for
    // rays = 0, InternalError when Embree cannot start. The scene must outlive this.
    RaycastRowProvider(const Scene& scene, const RaycastOptions& options);
    ~RaycastRowProvider() override;

    std::uint32_t size() const override;
    std::string name() const override { return "raycast"; }
    // Parallel over rows (an OrderedRowPool of `threads` workers); results in list order on the
    // calling thread, which runs only the sink. compute_rows_staged runs the caller's finish on
    // the workers too, right after each row is cast (plans are never asked for: the ray caster
    // samples the whole sender, can_sample_sender is false).
    void compute_rows(std::span<const std::uint32_t> rows, const RowSink& sink) override;
    void compute_rows_staged(std::span<const std::uint32_t> rows, const RowStages& stages,
                             const RowSink& sink) override;

    // One row on the calling thread, for a caller with its own threads (the driver casts, on the
    // hemicube's worker threads, the rows planned at 4 × 4 sub-hemicubes: RowDriver,
    // pipeline/row_engine.hpp). The same row compute_rows makes. Thread-safe: any number at
    // once, each with its own scratch.
    struct RowScratch {
        std::vector<double> acc;  // one per patch, all zero between rows
        std::vector<std::uint32_t> touched, points, sorted, start, order;
        // Rows refined to a tolerance: per patch its slot in cols (kNoSlot between rows), the
        // columns hit, and kReplicates weights per column.
        std::vector<std::uint32_t> slot, cols;
        std::vector<double> rep;
    };
    // What a row refined to the tolerance came to: its estimated error (t · σ of the largest
    // entry or of the sum, over the entries not replaced later) and its rays.
    struct RowFigures {
        double noise = -1;
        std::uint64_t rays = 0;
    };
    void cast_row(std::uint32_t i, SparseRow& out, RowScratch& scratch) const;

    std::uint64_t rays() const;
    double tolerance() const;
    unsigned threads() const;
    // What the provider did so far (RaycastStats, above); merge_stats adds another's (an MPI
    // rank's) to this one's.
    RaycastStats stats() const;
    void merge_stats(const RaycastStats& other);

    // Ray origins sit this far in front of the patch, as a fraction of the patch's longest edge
    // (relative, never absolute units), but at least kMinOffset of the scene's extent: Embree
    // works in float, and an offset below a few float ulps of the (centred, unit-scaled)
    // coordinates would be rounded away.
    static constexpr double kOriginOffset = 1e-6;
    static constexpr double kMinOffset = 4e-7;
    static constexpr std::uint32_t kNoSlot = 0xFFFFFFFFu;

private:
    struct Impl;
    std::unique_ptr<Impl> impl_;
};

}  // namespace ffcube
