// Near-field analytic correction of form-factor rows (issue 7).
//
// A hemicube (and any one-point-per-sender method) measures F_ij from patch i's centre: the
// midpoint rule over the sender. Its error grows like (size/distance)² and is worst between
// patches that touch or nearly touch (shared edges, thin gaps), where it reaches percents of
// F_ij. CorrectedRowProvider wraps any RowProvider and, in each row it hands on, replaces the
// entries of near, provably unoccluded pairs by the exact polygon-to-polygon value
// (geometry/analytic.hpp, ff_polygon_polygon). Everything else is left as the inner provider
// made it.
//
//  * Near: |c_i − c_j| < k · max(size_i, size_j) (centroids, longest edges; k = 3 by default).
//    Beyond that the midpoint rule's relative error is about (size/distance)²/24·C ≲ 1e-3·F_ij
//    (docs/accuracy.md). Every near j is examined, whether or not the inner row has an entry
//    for it (a hemicube can miss a sliver next to a shared edge).
//  * Facing: j needs a vertex strictly in front of i's plane and i one in front of j's plane;
//    otherwise the exact value is 0 and so is what a hemicube sees: left alone, not counted.
//  * Unoccluded, decided soundly: a pair is replaced only when every other patch q whose
//    bounding box meets the pair's is separated from the convex hull of i ∪ j by a plane
//    (separating-axis test over a fixed set of candidate axes, touching allowed). Touching
//    contact lies in a supporting plane of the hull, which only segments lying in that plane can
//    meet: a set of measure zero, so such q block nothing (neighbours in the same plane, the back
//    side of a two-sided plate). When no separating axis is found the pair is refused (left as
//    the inner provider made it) and counted: the test never wrongly replaces, it may refuse a
//    pair that is in fact unoccluded.
// No GL here: the wrapper works on the rows of any provider, and results do not depend on the
// number of threads (each row's correction is a function of the scene and that row only).
#pragma once

#include <atomic>
#include <cmath>
#include <cstdint>
#include <memory>
#include <mutex>
#include <string>
#include <vector>

#include "ffcube/core/stats.hpp"
#include "ffcube/formfactor/row_provider.hpp"
#include "ffcube/scene/scene.hpp"

namespace ffcube {

class ExposedPoints;  // accuracy/exposed_points.hpp

struct NearFieldOptions {
    double k = 3.0;  // near: centroid distance < k × max(size_i, size_j); k > 0
    // Sender quadrature for the entries that are not near, for inner providers that sample the
    // sender at its centre only (the hemicube; not the ray caster, which samples the whole
    // patch): F_ij ← F_ij · Q_ij / M_ij, where M_ij is Lambert's point-to-polygon factor from
    // i's centroid (the midpoint rule the inner provider follows) and Q_ij the same factor
    // integrated over i by a degree-3 rule (2 × 2 Gauss on quads, weights by the bilinear
    // Jacobian; the 3-point degree-2 rule on triangles). For an unoccluded pair this turns the
    // midpoint rule's O((h/d)²) relative error into O((h/d)⁴) and keeps the inner provider's own
    // (pixel) error; for a partly occluded pair it scales the visible part by the unoccluded
    // ratio, an approximation (not proven; docs/accuracy.md). Not applied to near pairs (exact
    // or refused), nor where Q/M is outside 1 ± 0.25 (j straddles i's horizon: the inner value
    // is grazing pixels, not a midpoint value), nor to j at quadrature_k × max(size_i, size_j)
    // or more from i (the midpoint rule's relative error there, (h/d)²/24, is below 1e-5).
    bool sender_quadrature = false;
    double quadrature_k = 64.0;
    // Closed rows stay closed: when the inner row sums to 1 (within float storage), the
    // corrected row's non-exact entries share one factor so that it sums to 1 too; and an open
    // row pushed above 1 is scaled back to 1 the same way.
    bool keep_closed_rows = true;
    // The inner provider's noise, for the per-row error estimate: the largest ΔF of one hemicube
    // pixel, 4/(π N²) at resolution N (0: not a hemicube), or rays per row (0: not the ray caster).
    double pixel_delta_ff = 0;
    double rays = 0;
    // Rows with a near pair that may be occluded are asked of the inner provider as sub-hemicube
    // rows (a sampled RowProvider::RowRequest), when it can make them.
    bool sub_hemicubes = true;
    // Which refused (possibly occluded) near pairs need sub-hemicubes: those whose centre value
    // may be off by more than 5e-4 (docs/accuracy.md, "Which near pairs need sub-hemicubes").
    // The midpoint rule's error on F_ij is at most (size_i/δ)²/20, δ the distance from i's
    // centroid to polygon j: the sender's extent matters, not the receiver's. So a refused pair
    // asks for them when δ < sub_hemicube_k × size_i (10: (1/10)²/20 = 5e-4), or when i
    // straddles j's plane and its first-order bound (size_i/δ)·min(1, A_j/(πδ²)) exceeds 5e-4.
    // 0: every refused near pair (the policy before issue 15).
    double sub_hemicube_k = 10.0;
    // ... and so are rows whose sender has an occluder beside it (a patch within the near range
    // that rises in front of its plane with scene behind it: a ground cell beside a wall), where
    // what the centre sees is not what the sender sees on average (docs/accuracy.md, "Senders
    // beside an occluder"; accuracy/sender_visibility.hpp). Only with sub_hemicubes.
    bool sample_beside_occluders = true;
    // ... and, where the far field ran, rows with a facing pair beyond the near range that it
    // could not prove unoccluded: a far occluder's shadow moves across the receivers as the
    // point on the sender moves (a wall cell seeing the ground past another building), which
    // the centre's single visibility and the unoccluded quadrature ratio miss.
    bool sample_unproven_rows = true;
    // Far field: every facing pair beyond the near range whose visibility the plane test proves
    // (NearFieldCorrector::far_unoccluded) gets its analytic value too (docs/accuracy.md, "Far
    // field"): exact receiver and 3 × 3 sender rule within 5 sizes, the point kernel on 3 × 3,
    // 2 × 2 or 1 points per patch beyond. It costs O(patches) per row. off; on (wherever the
    // scene has at most 256 planes); automatic: on where the cost per row, estimated from the
    // geometry of a sample of rows (far_field_cost), is at most far_field_budget_ns plus
    // far_field_row_ns (the inner provider's cost of a row) times the share of sampled rows the
    // far field makes complete (those are not measured at all: skip_complete_rows).
    enum class FarField { off, automatic, on };
    FarField far_field = FarField::off;
    double far_field_budget_ns = 0;
    double far_field_row_ns = 0;
    // A row whose every facing pair has an analytic value (near pairs exact, far pairs proven:
    // NearAnalysis::complete) needs no measurement: it is not asked of the inner provider at
    // all (RowPlan::skip), when the provider can be asked (sub_hemicubes and can_sample_sender).
    bool skip_complete_rows = true;
    // Exact values also for obstruction-only patches (Scene::obstruction_first, two faces back to
    // back) that a patch faces. Right for an inner provider that credits the facing one of the
    // two (the hemicube, which never draws a back face with a twin); false for one that credits
    // whichever it hits, front or back (the ray caster): their entries then stay as measured.
    bool obstruction_receivers = true;
    // Exact visibility (issue 14/15; docs/accuracy.md, "Exact visibility past a few occluders"):
    // a refused near pair that asks for sub-hemicubes (sub_hemicube_k) and whose shaft holds at
    // most this many possible blockers, all convex (as are i and j), gets the exact factor past
    // them (geometry/visible_ff.hpp: the point factor to the visible part, integrated adaptively
    // over i) instead of being refused. 0: off (the struct's default; the command line's is
    // auto: K = 8 within exact_visibility_budget, below; an explicit `--exact-visibility K`: no budget).
    std::size_t exact_visibility_occluders = 0;
    double exact_visibility_tolerance = 1e-6;  // the adaptive rule's tolerance on F_ij
    // Automatic exact visibility (`--exact-visibility auto`, the hemicube's default): > 0 bounds
    // the work per row, in point-kernel evaluations × possible occluders (the kernel's cost is
    // about linear in the occluders) per hemicube the exact values spare the row (16 or 4 sub-
    // hemicubes against one or none; exact_visibility_budget_for_hemicube derives it from a
    // hemicube row's cost). Then a row's refused pairs that ask for sub-hemicubes are tried only
    // where resolving all of them spares the row its sub-hemicubes (no occluder beside the
    // sender, no unproven far pair, or the row becomes complete), in patch order, each only if
    // its least cost (visible_ff_min_points) fits what is left of the budget, its adaptive rule
    // capped at the rest; the first that does not fit or does not converge stops the row (the
    // rest stay refused: NearAnalysis::exact_visibility_over_budget). Deterministic: the budget
    // counts evaluations, not time. 0: no bound, every eligible pair tried (an explicit K).
    double exact_visibility_budget = 0;
    // The far field on the emitting rows only (`ffcube solve --far-field-emitters`, on by
    // default there; docs/adaptive.md, "The default within 0.1%"): where automatic mode finds the
    // far field over its budget for every row, it stays on for the rows of emitting patches
    // (Ke > 0), when their cost, n_E × the estimated cost per row, fits the budget of the whole
    // run, n × far_field_budget_ns. Those rows carry the direct term (half of each object's
    // radiosity in a room lit by a lamp), where the hemicube's far entries are off by up to 0.24%
    // on the Cornell box and the analytic values are exact. Off: the far field as before.
    bool far_field_emitters = false;
    // Near pairs worth an exact value, for an inner provider whose entries are unbiased with
    // noise that grows with the entry (the ray caster: variance ≤ F(1 − F)/rays): a near pair
    // whose unoccluded factor is provably below min_near_value, A_j / (π gap²) < min_near_value
    // (gap = centroid distance − both bounding radii > 0: no point of i is nearer j than gap, and
    // j subtends at most A_j / gap² there, F ≤ Ω/π), keeps its measured entry without a shaft
    // test or an exact value. Such a pair would remove at most min_near_value / rays of the row's
    // variance; on a city most are far-reaching wall triangles that other buildings block, whose
    // shaft tests were a third of the run (docs/accuracy.md, "Which near pairs the rays keep").
    // 0: every near pair (the hemicube's: its near error is a bias, not noise).
    double min_near_value = 0;
    // (New fields go last: tests initialise the first ones by position, {k, sender_quadrature}.)
};

// The options `--correct near` uses on rows of a hemicube at resolution N: sender quadrature,
// pixel noise, and the far field in automatic mode with a budget of 30% of a hemicube row's
// cost (3N² pixels at pixel_ns each: about 5 ns on llvmpipe here, docs/benchmarks.md). cpu_scale:
// the CPU's time at the analytic work against the development machine's, whose nanoseconds the
// far field's cost model counts (pipeline/cost_model.hpp; `ffcube calibrate` measures both).
NearFieldOptions near_field_options_for_hemicube(int resolution, double k = 3.0, double pixel_ns = 5.0,
                                                 double cpu_scale = 1.0);

// `--exact-visibility auto` on rows of a hemicube at resolution N: the per-row budget of
// NearFieldOptions::exact_visibility_budget (derivation beside its definition) and the K it uses.
// pixel_ns and cpu_scale as for near_field_options_for_hemicube.
double exact_visibility_budget_for_hemicube(int resolution, double pixel_ns = 5.0, double cpu_scale = 1.0);
inline constexpr std::size_t kAutoExactVisibilityOccluders = 8;

// What the correction did, summed over rows (and threads), declared once each with its report
// key and merge rule (core/stats.hpp): merged, flattened and reported from this list.
#define FFCUBE_NEAR_FIELD_STATS(X)                                                                                  \
    X(std::uint64_t, rows, sum, "corrections.rows")                     /* rows passed through */                  \
    X(std::uint64_t, rows_touched, sum, "corrections.rows_touched")     /* rows with a replaced entry */           \
    X(std::uint64_t, near_pairs, sum, "corrections.near_pairs")         /* near, facing pairs examined */          \
    X(std::uint64_t, replaced, sum, "corrections.entries_replaced")     /* entries replaced by the exact value */  \
    /* near, facing pairs left alone: possibly occluded */                                                          \
    X(std::uint64_t, refused, sum, "corrections.pairs_refused_possibly_occluded")                                  \
    /* near, facing pairs left as measured: below min_near_value */                                                 \
    X(std::uint64_t, below_value, sum, "corrections.near_pairs_below_value")                                       \
    X(std::uint64_t, quadrature, sum, "corrections.entries_quadrature") /* rescaled by the sender quadrature */     \
    /* rows with an entry within quadrature_k sizes */                                                              \
    X(std::uint64_t, rows_quadrature, sum, "corrections.rows_quadrature")                                          \
    /* rows that triggered nothing, handed on as they were */                                                       \
    X(std::uint64_t, rows_untouched, sum, "corrections.rows_untouched")                                            \
    X(std::uint64_t, rows_closed, sum, "corrections.rows_closed_rebalanced") /* closed rows rebalanced to 1 */     \
    /* open rows the correction pushed above 1, scaled to 1 */                                                      \
    X(std::uint64_t, rows_capped, sum, "corrections.rows_capped_at_one")                                           \
    /* Corrected rows out of range (an entry < 0, > 1 or not finite, or a sum above 1 beyond the                    \
       row's tolerance: src/accuracy/row_range.hpp) handed on as measured (docs/robustness.md). */                  \
    X(std::uint64_t, rows_recomputed_out_of_range, sum, "corrections.rows_recomputed_out_of_range")                \
    /* refused pairs that ask for sub-hemicubes (sub_hemicube_k) */                                                 \
    X(std::uint64_t, refused_sampled, sum, "corrections.pairs_refused_sub_hemicubes")                              \
    /* rows measured by sub-hemicubes (either reason below); of which for an occluder beside the                    \
       sender only; at 4 x 4 points (an occluder touches the sender); for far pairs not proven                      \
       unoccluded only */                                                                                           \
    X(std::uint64_t, rows_sampled, sum, "corrections.rows_sub_hemicubes")                                          \
    X(std::uint64_t, rows_sampled_occluder, sum, "corrections.rows_sub_hemicubes_occluder")                        \
    X(std::uint64_t, rows_sampled_fine, sum, "corrections.rows_sub_hemicubes_4x4")                                 \
    X(std::uint64_t, rows_sampled_unproven, sum, "corrections.rows_sub_hemicubes_unproven")                        \
    /* Receivers worth fewer than 4 of the largest hemicube pixels (F_ij < 4 pixel_delta_ff), as                    \
       the inner provider made them: detected and counted, not corrected. */                                        \
    X(std::uint64_t, small_receiver_entries, sum, "corrections.small_receiver_entries")                            \
    X(std::uint64_t, rows_with_small_receivers, sum, "corrections.rows_with_small_receivers")                      \
    /* Far field (NearFieldOptions::far_field): rows given analytic values beyond the near range,                   \
       entries so replaced (or added: the hemicube had no pixel for them), and facing pairs beyond                  \
       the near range whose visibility the plane test could not prove (kept as made); the same of                   \
       senders cut by a receiver's plane. */                                                                        \
    X(std::uint64_t, far_rows, sum, "corrections.far_field_rows")                                                  \
    X(std::uint64_t, far_entries, sum, "corrections.far_field_entries")                                            \
    X(std::uint64_t, far_unproven, sum, "corrections.far_field_pairs_unproven")                                    \
    X(std::uint64_t, cut_sender_entries, sum, "corrections.cut_sender_entries")                                    \
    X(std::uint64_t, cut_sender_unproven, sum, "corrections.cut_sender_pairs_unproven")                            \
    /* rows made wholly of analytic values, not measured at all */                                                  \
    X(std::uint64_t, rows_analytic, sum, "corrections.rows_analytic")                                              \
    /* refused near pairs given the exact value past their occluders, the point-kernel                              \
       evaluations they took, and those tried whose tolerance was not reached (left refused) */                     \
    X(std::uint64_t, exact_visibility, sum, "corrections.pairs_exact_visibility")                                  \
    X(std::uint64_t, exact_visibility_points, sum, "corrections.exact_visibility_points")                          \
    X(std::uint64_t, exact_visibility_unconverged, sum, "corrections.exact_visibility_unconverged")                \
    /* Automatic mode (exact_visibility_budget > 0): refused pairs not tried or stopped because the                 \
       row's budget would be exceeded, and rows where some pair was made exact. */                                  \
    X(std::uint64_t, exact_visibility_over_budget, sum, "corrections.exact_visibility_over_budget")                \
    X(std::uint64_t, exact_visibility_rows, sum, "corrections.exact_visibility_rows")                              \
    /* sum of points x possible occluders (what the budget counts) */                                               \
    X(double, exact_visibility_cost, sum, "corrections.exact_visibility_cost")                                     \
    /* largest |factor - 1| of the closed rows' rebalancing */                                                      \
    X(double, closed_scale_max_change, max, "corrections.rebalance_max_change")                                    \
    /* seconds spent correcting, summed over threads (inner provider excluded); of which (CPU                       \
       seconds, any thread) the near analysis and exact values; the sender quadrature ratios and                    \
       the error estimate */                                                                                        \
    X(double, seconds, sum, "corrections.seconds")                                                                 \
    X(double, near_seconds, sum, "corrections.near_seconds")                                                       \
    X(double, quadrature_seconds, sum, "corrections.quadrature_seconds")                                           \
    /* Smallest row sum as the inner provider made it (CorrectedRowProvider only; +inf before any                   \
       row): whether light escapes is a property of the uncorrected rows, since replacing noisy                     \
       near entries by exact ones moves ray-cast row sums of a closed scene off 1. (Not in the                      \
       report: the enforcement's closure evidence reads it.) */                                                     \
    X(double, inner_row_sum_min, min, "")

struct NearFieldStats {
    FFCUBE_STATS(NearFieldStats, FFCUBE_NEAR_FIELD_STATS)
};

// The near pairs of one row (NearFieldCorrector::analyse).
// The measuring noise of a row's entries, as RowErrorModel::noise gives each (about one standard
// deviation of the entry's error): of the entries the correction kept, their sum (what the L1
// estimate counts) and their largest; the noise of the row's sky share (1 − its measured sum),
// modelled as that of a receiver of that value; and the sum of the squares of the noise of the
// entries replaced by exact values. The tolerance's estimate (largest entry, row sum) is made from
// these (RowSide::tolerance_error).
struct RowNoise {
    double l1 = 0, max = 0, sky = 0, replaced_sum_sq = 0;
    void add(double sigma) {
        l1 += sigma;
        max = sigma > max ? sigma : max;
    }
};

struct NearAnalysis {
    std::vector<std::pair<std::uint32_t, double>> exact;  // (j, exact F_ij), j increasing
    std::uint64_t near_pairs = 0;                         // near, facing pairs examined
    std::uint64_t refused = 0;                            // of which possibly occluded
    std::uint64_t below_value = 0;                        // not counted there: below min_near_value
    std::uint64_t refused_sampled = 0;                    // of which asking for sub-hemicubes
    std::uint64_t far_entries = 0;                        // of `exact`, beyond the near range
    std::uint64_t far_unproven = 0;                       // facing pairs beyond it, not proven
    std::uint64_t cut_sender_entries = 0;  // of `exact`, beyond the near range, the sender cut by j's plane
    std::uint64_t cut_sender_unproven = 0;  // such pairs not proven unoccluded (left as measured)
    std::uint64_t exact_visibility = 0;                   // near pairs exact past their occluders
    std::uint64_t exact_visibility_points = 0;
    std::uint64_t exact_visibility_unconverged = 0;
    std::uint64_t exact_visibility_over_budget = 0;        // left refused by the row's budget
    double exact_visibility_cost = 0;  // Σ points × possible occluders: what the budget counts
    bool far = false;                                     // the far field was computed
    // Every facing pair of the row has its value here (far field on, nothing refused or
    // unproven): the row is known without measuring it.
    bool complete = false;
    // The patch faces an obstruction-only patch (Scene::obstruction_first): those are occluders,
    // never receivers here, so their entries stay as measured and the row must be measured.
    bool faces_obstruction = false;
    bool skipped = false;  // and the inner provider was told not to measure it
    // plan_row asked for sub-hemicubes: a near pair may be occluded (refused > 0), or an
    // occluder stands beside the sender (occluder 1: 2 × 2 sub-hemicubes; 2, touching it: 4 × 4).
    bool sampled = false;
    std::uint8_t occluder = 0;
    bool sampled_unproven = false;  // sampled for far pairs not proven unoccluded only
    double far_error = 0;  // Σ of the error bounds of its integrated values (far and separated near)
    double seconds = 0;                                   // spent making it
    // The inner provider's own estimate of its measuring error on the row (a ray caster refining
    // to a tolerance: RowProvider::RowStages::measured), −1 when it gave none.
    double measured_error = -1;
    double measured_rays = 0;  // and its rays (0: none given)
    // The pixel of the hemicube that measured the row, as the ΔF of the largest one, where it was
    // drawn again at a finer resolution (CorrectedRowProvider::refine_with); −1: the options'.
    double pixel_delta_ff = -1;
    bool done = false;
};

// Scratch space for analysing and correcting rows on one thread: buffers reused from row to row
// (no heap allocation per row once they have grown). Not thread-safe: one per thread.
class NearFieldScratch {
public:
    NearFieldScratch();
    ~NearFieldScratch();
    NearFieldScratch(NearFieldScratch&&) noexcept;
    NearFieldScratch& operator=(NearFieldScratch&&) noexcept;
    struct Buffers;  // src/accuracy/scratch.hpp
    Buffers& buffers() { return *buffers_; }

private:
    std::unique_ptr<Buffers> buffers_;
};

// Finds near pairs and decides occlusion for one scene. Builds a uniform grid of the patches'
// bounding boxes once (O(patches)); thread-compatible (const after construction).
class NearFieldCorrector {
public:
    NearFieldCorrector(const Scene& scene, const NearFieldOptions& options);
    ~NearFieldCorrector();
    NearFieldCorrector(const NearFieldCorrector&) = delete;
    NearFieldCorrector& operator=(const NearFieldCorrector&) = delete;

    // The near pairs of row i: exact values of those proven unoccluded, counts. Thread-safe.
    void analyse(std::uint32_t i, NearAnalysis& out) const;
    // The same with the caller's scratch space (out's buffer is reused too).
    void analyse(std::uint32_t i, NearAnalysis& out, NearFieldScratch& scratch) const;
    // How row i must be measured, from its analysis (made into out): sampled (sub-hemicubes)
    // when a near pair may be occluded or (NearFieldOptions::sample_beside_occluders) an occluder
    // stands beside the sender and not every pair is known (out.sampled, out.occluder;
    // sampled_fine when the occluder touches the sender), skip when every facing pair is known analytically (and
    // NearFieldOptions::skip_complete_rows; out.skipped is then set), centre otherwise. A
    // function of the scene and i only, so it may run before the row is asked of anyone.
    RowProvider::RowPlan plan_row(std::uint32_t i, NearAnalysis& out, NearFieldScratch& scratch) const;
    // Corrects row i in place (columns stay strictly increasing, values > 0) and adds to stats
    // (all but seconds). With error_estimate: the row's estimated error Σ_j |F_ij − exact_ij|
    // (docs/accuracy.md, "Per-row error estimate"). analysis: row i's, if already made.
    // sampled_row: the inner row is the average of sub-hemicubes at i's 2 × 2 quadrature points
    // (no sender quadrature ratio on top). cast_rays > 0 (with sampled_row): it was ray-cast from
    // the whole sender with that many rays instead (RowProvider::cast_fine_row_rays), so its
    // error estimate is the rays' noise, with no pixel noise and no quadrature residual. The
    // inner row of a skipped complete analysis (NearAnalysis::skipped) is empty: the row is the
    // analysis.
    void correct(std::uint32_t i, SparseRow& row, NearFieldStats& stats, double* error_estimate = nullptr,
                 const NearAnalysis* analysis = nullptr, bool sampled_row = false) const;
    // The same with the caller's scratch space: no heap allocation in the steady state.
    void correct(std::uint32_t i, SparseRow& row, NearFieldStats& stats, NearFieldScratch& scratch,
                 double* error_estimate = nullptr, const NearAnalysis* analysis = nullptr,
                 bool sampled_row = false, double cast_rays = 0, RowNoise* noise = nullptr) const;
    // True when no patch other than i and j can block any segment from i to j (see above).
    bool provably_unoccluded(std::uint32_t i, std::uint32_t j) const;
    // The far field's visibility proof, O(1) per pair for scenes of few planes: no plane that
    // holds patches separates a point of i from a point of j, except where the pair's hull
    // crosses it outside the bounding box of that plane's patches. False when the far field is
    // off for this scene (see far_field_planes).
    bool far_unoccluded(std::uint32_t i, std::uint32_t j) const;
    // Distinct planes of the scene's patches when the far field is on (0: off).
    std::size_t far_field_planes() const;
    // Whether the far field is on and why, in words, for the run's report and log.
    const std::string& far_field_status() const;
    // "auto" (a per-row budget), "off", or K (every eligible pair, no budget).
    std::string exact_visibility_mode() const;
    // Estimated far-field cost of a row (ns on one core of these machines; NAN when not estimated).
    double far_field_cost_ns() const;

private:
    struct Impl;
    std::unique_ptr<Impl> impl_;
};

class CorrectedRowProvider final : public RowProvider {
public:
    // inner and scene must outlive this; inner.size() == scene.size() (InputError otherwise,
    // also for k ≤ 0).
    CorrectedRowProvider(const Scene& scene, RowProvider& inner, const NearFieldOptions& options = {});
    ~CorrectedRowProvider() override;
    std::uint32_t size() const override { return inner_.size(); }
    std::string name() const override { return inner_.name(); }
    void compute_rows(std::span<const std::uint32_t> rows, const RowSink& sink) override;
    const NearFieldStats& stats() const { return stats_; }
    // Adds another process's statistics to these (an MPI rank's, merged onto rank 0's).
    void merge_stats(const NearFieldStats& other) { stats::merge(stats_, other); }
    // Each row handed on carries its figures (SparseRow::side): error, the estimated
    // Σ_j |F_ij − exact_ij|; tolerance_error, the estimate the tolerance is held to
    // (docs/accuracy.md, "Accuracy by target"): of the larger of the row's largest entry error and
    // its sum error. A row whose inner provider measured its own error (rays refined to a
    // tolerance) has that plus the correction's terms; any other has the correction's terms plus
    // kNoiseDeviations × the larger of its largest entry's modelled noise and the root sum of
    // squares of all of them; measure, how it was measured (RowMeasure).
    static constexpr double kNoiseDeviations = 3.0;
    // How a row was measured (RowSide::measure).
    enum RowMeasure : std::int8_t {
        not_computed = -1,
        analytic = 0,           // every pair known: not measured (NearAnalysis::skipped)
        centre = 1,             // one hemicube (or whatever the inner provider does) at the centre
        sampled_near_pair = 2,  // sub-hemicubes: a near pair may be occluded
        sampled_occluder = 3,   // 2 × 2 sub-hemicubes: an occluder beside the sender
        sampled_touching = 4,   // 4 × 4 sub-hemicubes: an occluder touching the sender
        sampled_unproven = 5,   // 2 × 2 sub-hemicubes: far pairs not proven unoccluded
        refined = 6,            // measured again by rays (refine_with): its estimate was above the target
        redrawn = 7,            // drawn again at a finer resolution (refine_with), and no more
    };
    const NearFieldCorrector& corrector() const { return corrector_; }
    // Accuracy by target for an inner provider that does not refine its rows (the hemicube): a
    // row measured by it whose tolerance estimate is above `tolerance` is measured again by each
    // refiner in turn until its estimate meets the tolerance (docs/accuracy.md, "Hemicube rows
    // above the target"). A refiner with pixel_delta_ff > 0 draws the row again with the same
    // plan at a finer resolution, whose largest pixel is that ΔF (a hemicube provider that can
    // sample the sender); the row is corrected again with its noise modelled at that pixel. Rows
    // the inner provider ray-cast (fine rows) are not drawn again. A refiner with pixel_delta_ff
    // == 0 must refine its rows to the tolerance and say what its measuring error came to through
    // RowStages::measured (the ray caster with RaycastOptions::tolerance); the row is then
    // corrected as that provider's (its rays' error, no pixels, no quadrature residual).
    // Called from the inner provider's workers, one row at a time, so a refiner must allow
    // concurrent single-row calls. The refiners must outlive this; empty: none.
    struct Refiner {
        RowProvider* provider = nullptr;
        double pixel_delta_ff = 0;
    };
    void refine_with(std::vector<Refiner> refiners, double tolerance) {
        refiners_ = std::move(refiners);
        refine_tolerance_ = tolerance;
    }
    // Rows measured again by rays so far, and rows drawn again at a finer resolution (a row drawn
    // at two finer resolutions counts once).
    std::uint64_t rows_refined() const { return rows_refined_.load(); }
    std::uint64_t rows_redrawn() const { return rows_redrawn_.load(); }
    // Entries still held by the analyses of rows already handed on (0 after compute_rows: each
    // row's analysis, up to a whole row with the far field, is freed once the row is corrected).
    std::size_t retained_analysis_entries() const {
        std::size_t n = 0;
        for (const NearAnalysis& a : analyses_) n += a.exact.size();
        return n;
    }

    // "patch I (object 'NAME')": the range check's messages, the report's rows above the tolerance.
    std::string patch_name(std::uint32_t i) const;

private:
    std::string out_of_range_message(std::uint32_t i, const SparseRow& row, bool analytic) const;
    void warn_out_of_range();
    // The sender points and weights of sampled row i into request (the plan's sender rule).
    void sender_points(std::uint32_t i, RowRequest& request);

    RowProvider& inner_;
    const Scene& scene_;
    NearFieldCorrector corrector_;
    NearFieldStats stats_;
    std::vector<Refiner> refiners_;
    double refine_tolerance_ = 0;
    std::atomic<std::uint64_t> rows_refined_{0};
    std::atomic<std::uint64_t> rows_redrawn_{0};
    NearFieldOptions options_;
    std::vector<NearAnalysis> analyses_;  // of the rows of the current compute_rows call
    // Scratch spaces and analysis buffers reused across rows, one per row being planned or
    // corrected at once on the inner provider's threads (corrected_row_provider.cpp).
    struct Pools;
    std::unique_ptr<Pools> pools_;
    // Points on the exposed part of cut senders (accuracy/exposed_points.hpp), made at the first
    // sampled row.
    std::once_flag exposed_once_;
    std::unique_ptr<ExposedPoints> exposed_;
};

}  // namespace ffcube
