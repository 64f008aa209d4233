// NearFieldCorrector: one row's analysis (its near pairs, exact where proven unoccluded, and
// the far field's entries), its plan, and its correction as named steps over the pieces of
// src/accuracy (patch_set, spatial_grid, shaft_test, near_values, far_field, sender_quadrature,
// row_merge, rebalance, row_error). CorrectedRowProvider is in corrected_row_provider.cpp.
#include "ffcube/accuracy/near_field.hpp"

#include <fmt/format.h>
#include <glm/geometric.hpp>

#include <algorithm>
#include <numbers>

#include "accuracy/far_field.hpp"
#include "accuracy/near_values.hpp"
#include "accuracy/patch_set.hpp"
#include "accuracy/rebalance.hpp"
#include "accuracy/row_error.hpp"
#include "accuracy/row_merge.hpp"
#include "accuracy/scratch.hpp"
#include "accuracy/sender_quadrature.hpp"
#include "accuracy/sender_visibility.hpp"
#include "accuracy/shaft_test.hpp"
#include "accuracy/spatial_grid.hpp"
#include "ffcube/core/error.hpp"
#include "ffcube/core/timer.hpp"
#include "ffcube/geometry/visible_ff.hpp"

namespace ffcube {

namespace {

// Every facing pair of the row has its value (with the far field on): nothing refused or unproven,
// no obstruction in sight.
bool known_without_measuring(const NearAnalysis& a) {
    return a.refused == 0 && a.below_value == 0 && a.far_unproven == 0 && !a.faces_obstruction;
}

}  // namespace

using namespace accuracy;

NearFieldScratch::NearFieldScratch() : buffers_(std::make_unique<Buffers>()) {}
NearFieldScratch::~NearFieldScratch() = default;
NearFieldScratch::NearFieldScratch(NearFieldScratch&&) noexcept = default;
NearFieldScratch& NearFieldScratch::operator=(NearFieldScratch&&) noexcept = default;

struct NearFieldCorrector::Impl {
    Impl(const Scene& s, const NearFieldOptions& o)
        : options(o), patches(s), grid(patches), far(patches, grid, options), visibility(patches, grid, options.k) {}

    const NearFieldOptions options;
    const PatchSet patches;
    const SpatialGrid grid;
    const FarField far;
    const SenderVisibility visibility;

    bool needs_sub_hemicubes(std::uint32_t i, std::uint32_t j) const;
    void add_near_pairs(std::uint32_t i, NearAnalysis& out, NearFieldScratch::Buffers& b) const;
    void add_far_pairs(std::uint32_t i, NearAnalysis& out, NearFieldScratch::Buffers& b) const;
    void add_cut_sender_pairs(std::uint32_t i, NearAnalysis& out, NearFieldScratch::Buffers& b) const;
    // F_ij of a facing pair proven unoccluded, each patch clipped to the other's front.
    double pair_value(std::uint32_t i, std::uint32_t j, double d, NearAnalysis& out, NearFieldScratch::Buffers& b) const;
    // The plane test for a sender cut by j's plane, on its part in front of j (FarField::unoccluded_front).
    bool cut_sender_unoccluded(std::uint32_t i, std::uint32_t j, NearFieldScratch::Buffers& b) const {
        const Patch& pj = patches.scene.patches[j];
        clip_front(patches.polys[i].span(), pj.centroid, pj.normal, b.front);
        return far.unoccluded_front(b.front, i, j);
    }
    enum class Exact { made, refused, over_budget };
    // budget: what is left of the row's (auto mode), or nullptr: no bound.
    Exact exact_visibility(std::uint32_t i, std::uint32_t j, NearAnalysis& out, NearFieldScratch::Buffers& b,
                           double* budget = nullptr) const;
    // The exact value of an eligible pair from its clipped sender and occluders (what
    // exact_visibility_eligible left in b.sender, b.occluders) and its least cost.
    Exact evaluate_visible(std::uint32_t i, std::uint32_t j, NearAnalysis& out, const std::vector<Vec3>& sender,
                           const std::vector<std::vector<Vec3>>& occluders, double least, double* budget) const;
    // The row's occluder level (plan_row), computed once per analysis from b.near as the near-pair
    // search left it.
    int occluder_level(std::uint32_t i, NearFieldScratch::Buffers& b) const;
    // Whether pair (i, j) may be tried (its shaft's blockers, convexity, the sender's front part in
    // b.blockers and b.sender), and its least cost in evaluations × occluders.
    bool exact_visibility_eligible(std::uint32_t i, std::uint32_t j, NearFieldScratch::Buffers& b, double& least) const;
    void resolve_deferred(std::uint32_t i, NearAnalysis& out, NearFieldScratch::Buffers& b) const;
    bool automatic() const { return options.exact_visibility_budget > 0 && options.exact_visibility_occluders > 0; }
};

// A refused pair whose shaft holds at most exact_visibility_occluders possible blockers (every
// patch that no axis separates from the pair's hull: the rest cannot meet a segment from i to j),
// all convex: F_ij is the point factor to j's visible part past them, integrated over the part of i
// in front of j's plane (the rest sends nothing to j) and divided by A_i. Made into out.exact when
// the adaptive rule reaches its tolerance (its estimate joins the row's error as far_error).
bool NearFieldCorrector::Impl::exact_visibility_eligible(std::uint32_t i, std::uint32_t j, NearFieldScratch::Buffers& b,
                                                         double& least) const {
    const std::size_t k = options.exact_visibility_occluders;
    if (k == 0) return false;
    if (!shaft_blockers(patches, grid, i, j, b.shaft, b.blockers, k)) return false;
    if (!polygon_is_convex(patches.polys[i].span()) || !polygon_is_convex(patches.polys[j].span())) return false;
    b.occluders.resize(b.blockers.size());
    for (std::size_t q = 0; q < b.blockers.size(); ++q) {
        const auto poly = patches.polys[b.blockers[q]].span();
        if (!polygon_is_convex(poly)) return false;
        b.occluders[q].assign(poly.begin(), poly.end());
    }
    const Patch& pj = patches.scene.patches[j];
    clip_front(patches.polys[i].span(), pj.centroid, pj.normal, b.sender);
    if (b.sender.size() < 3) return false;
    least = static_cast<double>(visible_ff_min_points(b.sender.size())) *
            static_cast<double>(std::max<std::size_t>(1, b.blockers.size()));
    return true;
}

NearFieldCorrector::Impl::Exact NearFieldCorrector::Impl::exact_visibility(std::uint32_t i, std::uint32_t j,
                                                                           NearAnalysis& out,
                                                                           NearFieldScratch::Buffers& b,
                                                                           double* budget) const {
    double least = 0;
    if (!exact_visibility_eligible(i, j, b, least)) return Exact::refused;
    return evaluate_visible(i, j, out, b.sender, b.occluders, least, budget);
}

int NearFieldCorrector::Impl::occluder_level(std::uint32_t i, NearFieldScratch::Buffers& b) const {
    if (b.occluder_level < 0) b.occluder_level = visibility.occluder_level_of_candidates(i, b.near);
    return b.occluder_level;
}

NearFieldCorrector::Impl::Exact NearFieldCorrector::Impl::evaluate_visible(
    std::uint32_t i, std::uint32_t j, NearAnalysis& out, const std::vector<Vec3>& sender,
    const std::vector<std::vector<Vec3>>& occluders, double least, double* budget) const {
    VisibleFFOptions vo;
    vo.tolerance = options.exact_visibility_tolerance;
    // The kernel's cost grows about linearly with the occluders it cuts the receiver by.
    const double per_point = static_cast<double>(std::max<std::size_t>(1, occluders.size()));
    bool capped = false;
    if (budget) {
        if (least > *budget) return Exact::over_budget;
        const auto cap = static_cast<std::uint64_t>(*budget / per_point);
        capped = cap < vo.max_points;
        vo.max_points = std::min(vo.max_points, cap);
    }
    const VisibleFFResult r = ff_polygon_visible_polygon(sender, patches.polys[j].span(), occluders, vo);
    out.exact_visibility_points += r.points;
    out.exact_visibility_cost += static_cast<double>(r.points) * per_point;
    if (budget) *budget -= static_cast<double>(r.points) * per_point;
    if (!r.converged) {
        if (capped) return Exact::over_budget;
        ++out.exact_visibility_unconverged;
        return Exact::refused;
    }
    const double scale = polygon_area(sender) / patches.scene.patches[i].area;
    // Where the occluders hide j wholly the pieces' clipping leaves rounding (1e-20 under a plate
    // between two squares): a value below 1e-12, a millionth of the rule's tolerance, is 0 (no
    // entry), moved by less than 1e-12.
    const double f = r.f * scale < 1e-12 ? 0.0 : r.f * scale;
    out.exact.emplace_back(j, f);
    out.far_error += r.error * scale;
    ++out.exact_visibility;
    return Exact::made;
}

// Auto mode: the row's refused pairs that ask for sub-hemicubes (b.deferred, j increasing, all
// counted refused by add_near_pairs) are tried only where making all of them exact spares the row
// its sub-hemicubes: the row would become complete (not measured at all), or nothing else would
// sample it (an occluder beside the sender, a far pair not proven: plan_row). Elsewhere the
// sub-hemicubes are drawn anyway and measure those pairs to about 5e-4. All must be eligible and
// their least costs must fit the budget together; then they are made in order, each capped at
// what is left, and the first that does not fit stops the row.
void NearFieldCorrector::Impl::resolve_deferred(std::uint32_t i, NearAnalysis& out, NearFieldScratch::Buffers& b) const {
    const std::size_t n = b.deferred.size();
    if (n == 0) return;
    const bool unproven = options.sample_unproven_rows && out.far && out.far_unproven > 0;
    const bool would_complete = options.skip_complete_rows && out.far && out.far_unproven == 0 &&
                                !out.faces_obstruction && out.refused == n;
    const int level = options.sample_beside_occluders ? occluder_level(i, b) : 0;
    const bool would_centre = !unproven && level == 0;
    if (!would_complete && !would_centre) return;
    // The hemicubes spared: plan_row's 4 × 4 sub-hemicubes where an occluder touches the sender
    // (level 2), 2 × 2 otherwise, against none (complete: skipped) or the centre's one.
    const double spared = (level == 2 ? 16.0 : 4.0) - (would_complete ? 0.0 : 1.0);
    // Each pair's shaft search and clipping once: kept for the evaluation below.
    if (b.deferred_sender.size() < n) {
        b.deferred_sender.resize(n);
        b.deferred_occluders.resize(n);
    }
    b.deferred_least.resize(n);
    double least_sum = 0;
    for (std::size_t q = 0; q < n; ++q) {
        double least = 0;
        if (!exact_visibility_eligible(i, b.deferred[q], b, least)) return;  // the row is sampled whatever is done
        std::swap(b.deferred_sender[q], b.sender);
        std::swap(b.deferred_occluders[q], b.occluders);
        b.deferred_least[q] = least;
        least_sum += least;
    }
    double budget = options.exact_visibility_budget * spared;
    if (least_sum > budget) {
        out.exact_visibility_over_budget += n;
        return;
    }
    const std::size_t first = out.exact.size();
    for (std::size_t q = 0; q < n; ++q) {
        const Exact e = evaluate_visible(i, b.deferred[q], out, b.deferred_sender[q], b.deferred_occluders[q],
                                         b.deferred_least[q], &budget);
        if (e != Exact::made) {
            if (e == Exact::over_budget) out.exact_visibility_over_budget += n - q;
            break;
        }
        --out.refused;
        --out.refused_sampled;
    }
    if (out.exact.size() == first) return;
    std::sort(out.exact.begin(), out.exact.end(),
              [](const auto& a, const auto& c) { return a.first < c.first; });
    if (out.far) out.complete = known_without_measuring(out);
}

// Whether a refused pair's centre value may be off by more than e = (1/k)²/20 (k =
// sub_hemicube_k; 5e-4 at the default 10), so that its row needs sub-hemicubes (docs/accuracy.md,
// "Which near pairs need sub-hemicubes"). The hemicube measures g(x) = F_{dx_i→j} at i's centroid
// c; the midpoint rule's error on the mean of g over i is (1/2)·∫(x−c)ᵀH(x−c)/A_i ≤
// (size_i²/12)·|Δg|/2, and |Δg| ≤ 1.05/δ² (δ = |c − j|, measured over 10,000 random receivers of
// 0.1 to 50 sender sizes, any distance and orientation; the curvature comes from j's outline,
// which lies at least δ away): error ≤ (size_i/δ)²/23, taken as /20. So δ ≥ k·size_i keeps it
// below e, whatever j's size. Where i straddles j's plane, g is 0 behind it and the rule is only
// first order: the error is at most max g ≤ cos θ_j,max · min(1, Ω_j/π) ≤ (size_i/δ)·min(1,
// A_j/(πδ²)) (i's points lie within size_i of j's plane).
bool NearFieldCorrector::Impl::needs_sub_hemicubes(std::uint32_t i, std::uint32_t j) const {
    const double k = options.sub_hemicube_k;
    if (!(k > 0)) return true;  // the policy before issue 15: every refused pair
    const Patch& pi = patches.scene.patches[i];
    const double delta = patches.distance(pi.centroid, j);
    if (patches.straddles(i, j)) {
        const double area = patches.scene.patches[j].area;
        const double bound = pi.size / delta * std::min(1.0, area / (std::numbers::pi * delta * delta));
        return !(bound <= 1.0 / (20 * k * k));
    }
    return !(delta >= k * pi.size);
}

// Every facing pair within k sizes: exact when the shaft test proves it unoccluded (the 6 × 6
// rule when the pair's bounding spheres are well apart), refused otherwise; a refused pair
// asks for sub-hemicubes when its centre value may be too far off (needs_sub_hemicubes).
void NearFieldCorrector::Impl::add_near_pairs(std::uint32_t i, NearAnalysis& out, NearFieldScratch::Buffers& b) const {
    const Scene& scene = patches.scene;
    const Patch& pi = scene.patches[i];
    const double k = options.k;
    const double reach = k * std::max(pi.size, patches.max_size);
    grid.query(Box{pi.centroid - Vec3(reach), pi.centroid + Vec3(reach)}, b.near);
    b.deferred.clear();
    for (std::uint32_t j : b.near) {
        if (j == i) continue;
        const Patch& pj = scene.patches[j];
        const double d = glm::length(pj.centroid - pi.centroid);
        if (d >= k * std::max(pi.size, pj.size)) continue;
        if (!patches.facing(i, j)) continue;
        if (j >= scene.obstruction_first && !options.obstruction_receivers) {  // its entry stays as measured
            out.faces_obstruction = true;
            continue;
        }
        if (options.min_near_value > 0) {  // F_ij ≤ A_j / (π gap²): left as measured below the bound
            const double gap = d - patches.radius[i] - patches.radius[j];
            if (gap > 0 && pj.area < options.min_near_value * std::numbers::pi * gap * gap) {
                ++out.below_value;
                continue;
            }
        }
        ++out.near_pairs;
        if (!shaft_unoccluded(patches, grid, i, j, b.shaft)) {
            if (needs_sub_hemicubes(i, j)) {
                if (automatic()) {
                    b.deferred.push_back(j);  // tried after the far field: resolve_deferred
                } else if (exact_visibility(i, j, out, b) == Exact::made) {
                    continue;
                }
            }
            ++out.refused;
            out.refused_sampled += needs_sub_hemicubes(i, j);
            continue;
        }
        out.exact.emplace_back(j, pair_value(i, j, d, out, b));
    }
}

// b.far (columns increasing) merged into out.exact, which stays in increasing columns.
static void merge_far_into_exact(NearAnalysis& out, NearFieldScratch::Buffers& b) {
    b.near_exact.assign(out.exact.begin(), out.exact.end());
    out.exact.resize(b.near_exact.size() + b.far.size());
    std::merge(b.near_exact.begin(), b.near_exact.end(), b.far.begin(), b.far.end(), out.exact.begin());
}

double NearFieldCorrector::Impl::pair_value(std::uint32_t i, std::uint32_t j, double d, NearAnalysis& out,
                                            NearFieldScratch::Buffers& b) const {
    const Patch& pi = patches.scene.patches[i];
    const Patch& pj = patches.scene.patches[j];
    const double gap = d - patches.radius[i] - patches.radius[j];
    if (gap >= 2 * std::min(patches.radius[i], patches.radius[j])) {
        const double f = separated_ff(patches.polys[i], pi, patches.radius[i], patches.polys[j], pj, patches.radius[j], b.values);
        out.far_error += kSeparatedRelativeError * f;  // the 6 × 6 rule's measured worst, 3.6e-10, with margin
        return f;
    }
    return exact_ff(patches.polys[i], pi, patches.polys[j], pj);
}

// A sender cut by the plane of receivers beyond the near range (hemicube rows: the sender
// quadrature's case). Each receiver j of such a plane sees only the part of i in front of it,
// and the centre, where the hemicube stands, may lie behind it (it then sees nothing of j) or
// just in front (j at grazing pixels): neither is a midpoint value, and the quadrature's ratio
// cannot mend an entry the centre did not see. So those pairs get their value with i clipped
// to j's front where the plane test proves them unoccluded (the L-shaped room's walls beside
// the inner corner: docs/accuracy.md, "Senders cut by a receiver's plane"); the rest stay as
// measured and are counted. Merged into out.exact (columns increasing).
void NearFieldCorrector::Impl::add_cut_sender_pairs(std::uint32_t i, NearAnalysis& out, NearFieldScratch::Buffers& b) const {
    far.cutting_planes(i, b.cutting);
    if (b.cutting.empty()) return;
    const Scene& scene = patches.scene;
    const Patch& pi = scene.patches[i];
    b.far.clear();
    for (const std::uint32_t g : b.cutting) {
        for (const std::uint32_t j : far.members(g)) {
            if (j == i || j >= scene.obstruction_first) continue;
            const Patch& pj = scene.patches[j];
            const double d = glm::length(pj.centroid - pi.centroid);
            if (d < options.k * std::max(pi.size, pj.size) || !patches.facing(i, j)) continue;  // near: made above
            if (!cut_sender_unoccluded(i, j, b)) {
                ++out.cut_sender_unproven;
                continue;
            }
            b.far.emplace_back(j, pair_value(i, j, d, out, b));
        }
    }
    if (b.far.empty()) return;
    std::sort(b.far.begin(), b.far.end());
    out.cut_sender_entries += b.far.size();
    merge_far_into_exact(out, b);
}

// Far field: every other facing pair the plane test proves unoccluded, merged into out.exact
// (columns increasing); the rest counted as unproven.
void NearFieldCorrector::Impl::add_far_pairs(std::uint32_t i, NearAnalysis& out, NearFieldScratch::Buffers& b) const {
    const Scene& scene = patches.scene;
    const Patch& pi = scene.patches[i];
    out.far = true;
    b.far.clear();
    if (options.sender_quadrature) far.cutting_planes(i, b.cutting);
    else b.cutting.clear();
    const auto n = static_cast<std::uint32_t>(scene.size());
    for (std::uint32_t j = 0; j < n; ++j) {
        if (j == i) continue;
        const Patch& pj = scene.patches[j];
        const double d = glm::length(pj.centroid - pi.centroid);
        if (d < options.k * std::max(pi.size, pj.size) || !patches.facing(i, j)) continue;
        if (j >= scene.obstruction_first && !options.obstruction_receivers) {  // its entry stays as measured
            out.faces_obstruction = true;
            continue;
        }
        if (!b.cutting.empty() && std::find(b.cutting.begin(), b.cutting.end(), far.plane_of(j)) != b.cutting.end()) {
            // i cut by j's plane: i clipped to j's front (add_cut_sender_pairs)
            if (!cut_sender_unoccluded(i, j, b)) {
                ++out.far_unproven;
                ++out.cut_sender_unproven;
                continue;
            }
            b.far.emplace_back(j, pair_value(i, j, d, out, b));
            ++out.cut_sender_entries;
            continue;
        }
        if (!far.unoccluded(i, j)) {
            ++out.far_unproven;
            continue;
        }
        const auto [f, error] = far.value(i, j, d);
        b.far.emplace_back(j, f);
        out.far_error += error;
    }
    out.far_entries = b.far.size();
    out.complete = known_without_measuring(out);
    merge_far_into_exact(out, b);
}

NearFieldCorrector::NearFieldCorrector(const Scene& scene, const NearFieldOptions& options) {
    if (!(options.k > 0) || !std::isfinite(options.k))
        throw InputError(fmt::format("near-field correction: k = {} must be a positive number", options.k));
    if (!(options.sub_hemicube_k >= 0) || !std::isfinite(options.sub_hemicube_k))
        throw InputError(fmt::format("near-field correction: sub-hemicube k = {} must be a number >= 0",
                                     options.sub_hemicube_k));
    if (!(options.min_near_value >= 0 && options.min_near_value <= 1))
        throw InputError(fmt::format("near-field correction: min_near_value = {} must be a form factor, 0 to 1",
                                     options.min_near_value));
    impl_ = std::make_unique<Impl>(scene, options);
}

NearFieldCorrector::~NearFieldCorrector() = default;

NearFieldOptions near_field_options_for_hemicube(int resolution, double k, double pixel_ns, double cpu_scale) {
    NearFieldOptions o;
    o.k = k;
    o.sender_quadrature = true;
    const double n = resolution;
    o.pixel_delta_ff = 4.0 / (std::numbers::pi * n * n);
    // 30% of a hemicube row: 3N² pixels at about 5 ns each on one core of llvmpipe
    // (tools/bench_far_field prints both per row; docs/benchmarks.md), or pixel_ns as measured by
    // `ffcube calibrate`; in the development machine's CPU nanoseconds (÷ cpu_scale), which the
    // far field's cost model counts.
    o.far_field = NearFieldOptions::FarField::automatic;
    o.far_field_row_ns = 3.0 * n * n * pixel_ns / cpu_scale;
    o.far_field_budget_ns = 0.3 * o.far_field_row_ns;
    return o;
}

// `--exact-visibility auto`'s budget, in point-kernel evaluations × possible occluders per
// hemicube the exact values spare (resolve_deferred multiplies it by the row's: 15 or 16 for a
// row of 4 × 4 sub-hemicubes, 3 or 4 for one of 2 × 2, as it becomes one hemicube or none).
// - A hemicube row: 3N² pixels at 5 ns (far_field_row_ns; 0.98 ms at N = 256). Measured here:
//   the unsubdivided L-room without exact visibility, 132 hemicubes at N = 256 plus start-up,
//   0.09 CPU-s, so ≤ 0.7 ms each: the model does not understate it.
// - One evaluation × occluder: 650 ns (the L-room with `--exact-visibility 8 --threads 1`: near
//   analysis 0.23 s for 180,480 points × 2 occluders on average = 360,960; docs/benchmarks.md).
// - kSpentPerSpared = 4: the exact values may cost up to 4 times the hemicubes they spare. At 1
//   only 13 of the L-room's 28 pairs fit (its rows take 45,000 evaluations × occluders on
//   average against 24,000 for 16 hemicubes), at 4 all do; the exact value replaces an entry
//   that sub-hemicubes leave off by up to 6.6e-3 there (a 3 × 3 wall's 4 × 4 points cannot
//   follow where a corner starts to hide), against 1e-6. What it costs at worst: a row that
//   exhausts its budget and still needs its sub-hemicubes spends 4 × their cost on top; rows
//   are tried only where the least costs fit, so on the Cornell box (14 rows made exact, 5
//   pairs over budget) the run's CPU is unchanged (docs/benchmarks.md).
// - pixel_ns and cpu_scale (`ffcube calibrate`, pipeline/cost_model.hpp): another device's pixel and
//   another CPU's evaluation; 5 and 1 are this machine's.
double exact_visibility_budget_for_hemicube(int resolution, double pixel_ns, double cpu_scale) {
    constexpr double kSpentPerSpared = 4;
    constexpr double kEvaluationNs = 650;
    const double n = resolution;
    return kSpentPerSpared * 3.0 * n * n * pixel_ns / (kEvaluationNs * cpu_scale);
}

bool NearFieldCorrector::far_unoccluded(std::uint32_t i, std::uint32_t j) const { return impl_->far.unoccluded(i, j); }
std::size_t NearFieldCorrector::far_field_planes() const { return impl_->far.planes(); }
std::string NearFieldCorrector::exact_visibility_mode() const {
    if (impl_->options.exact_visibility_occluders == 0) return "off";
    if (impl_->automatic()) return "auto";
    return std::to_string(impl_->options.exact_visibility_occluders);
}
const std::string& NearFieldCorrector::far_field_status() const { return impl_->far.status(); }
double NearFieldCorrector::far_field_cost_ns() const { return impl_->far.cost_ns(); }

bool NearFieldCorrector::provably_unoccluded(std::uint32_t i, std::uint32_t j) const {
    ShaftScratch scratch;
    return shaft_unoccluded(impl_->patches, impl_->grid, i, j, scratch);
}

void NearFieldCorrector::analyse(std::uint32_t i, NearAnalysis& out) const {
    NearFieldScratch scratch;
    analyse(i, out, scratch);
}

void NearFieldCorrector::analyse(std::uint32_t i, NearAnalysis& out, NearFieldScratch& scratch) const {
    // Reset out, keeping its buffer.
    auto exact = std::move(out.exact);
    exact.clear();
    out = NearAnalysis{};
    out.exact = std::move(exact);
    Stopwatch watch;
    NearFieldScratch::Buffers& b = scratch.buffers();
    b.occluder_level = -1;
    impl_->add_near_pairs(i, out, b);
    if (impl_->far.applies(i)) impl_->add_far_pairs(i, out, b);
    else if (impl_->options.sender_quadrature) impl_->add_cut_sender_pairs(i, out, b);
    if (impl_->automatic()) impl_->resolve_deferred(i, out, b);
    out.seconds = watch.seconds();
    out.done = true;
}

RowProvider::RowPlan NearFieldCorrector::plan_row(std::uint32_t i, NearAnalysis& out, NearFieldScratch& scratch) const {
    analyse(i, out, scratch);
    // Every facing pair known: nothing to measure (RowPlan::skip hands on an empty row).
    if (out.complete && impl_->options.skip_complete_rows) {
        out.skipped = true;
        return RowProvider::RowPlan::skip;
    }
    // A near pair that may be occluded, or an occluder beside the sender: sub-hemicubes, at 4 × 4
    // points when the occluder touches the sender (refused near pairs included: the wall that
    // hides them is usually that occluder).
    if (impl_->options.sample_beside_occluders)
        out.occluder = static_cast<std::uint8_t>(impl_->occluder_level(i, scratch.buffers()));
    if (out.refused_sampled > 0 || out.occluder > 0) {
        out.sampled = true;
        return out.occluder == 2 ? RowProvider::RowPlan::sampled_fine : RowProvider::RowPlan::sampled;
    }
    if (impl_->options.sample_unproven_rows && out.far && out.far_unproven > 0) {
        out.sampled = out.sampled_unproven = true;
        return RowProvider::RowPlan::sampled;
    }
    return RowProvider::RowPlan::centre;
}

void NearFieldCorrector::correct(std::uint32_t i, SparseRow& row, NearFieldStats& stats, double* error_estimate,
                                 const NearAnalysis* analysis, bool sampled_row) const {
    NearFieldScratch scratch;
    correct(i, row, stats, scratch, error_estimate, analysis, sampled_row);
}

namespace {

void add_analysis_stats(const NearAnalysis& a, NearFieldStats& stats) {
    stats.near_pairs += a.near_pairs;
    stats.refused += a.refused;
    stats.below_value += a.below_value;
    stats.refused_sampled += a.refused_sampled;
    stats.far_rows += a.far;
    stats.far_entries += a.far_entries;
    stats.far_unproven += a.far_unproven;
    stats.cut_sender_entries += a.cut_sender_entries;
    stats.cut_sender_unproven += a.cut_sender_unproven;
    stats.rows_analytic += a.skipped;
    stats.exact_visibility += a.exact_visibility;
    stats.exact_visibility_points += a.exact_visibility_points;
    stats.exact_visibility_unconverged += a.exact_visibility_unconverged;
    stats.exact_visibility_over_budget += a.exact_visibility_over_budget;
    stats.exact_visibility_rows += a.exact_visibility > 0;
    stats.exact_visibility_cost += a.exact_visibility_cost;
    stats.near_seconds += a.seconds;
}

// Detection only: receivers worth fewer than 4 of the largest hemicube pixels are found only by
// the few pixels they happen to cover (no correction for them yet; docs/accuracy.md).
void count_small_receivers(const SparseRow& row, double pixel_delta_ff, NearFieldStats& stats) {
    if (!(pixel_delta_ff > 0)) return;
    std::uint64_t small = 0;
    for (const double f : row.val) small += f < 4 * pixel_delta_ff;
    stats.small_receiver_entries += small;
    stats.rows_with_small_receivers += small > 0;
}

}  // namespace

// The steps: the row's analysis (made here unless given), its statistics, whether the sender
// quadrature is needed; a row that needs nothing is handed on as it is, with its error estimate;
// otherwise the merge of the inner row with the analytic entries (rescaling the rest), the
// closed-row rebalancing, and the estimate.
void NearFieldCorrector::correct(std::uint32_t i, SparseRow& row, NearFieldStats& stats, NearFieldScratch& scratch,
                                 double* error_estimate, const NearAnalysis* analysis, bool sampled_row,
                                 double cast_rays, RowNoise* noise) const {
    const Impl& im = *impl_;
    NearFieldScratch::Buffers& b = scratch.buffers();
    ++stats.rows;
    if (!analysis || !analysis->done) {
        analyse(i, b.analysis, scratch);
        analysis = &b.analysis;
    }
    add_analysis_stats(*analysis, stats);
    Stopwatch quadrature_watch;
    if (sampled_row) {
        ++stats.rows_sampled;
        stats.rows_sampled_occluder += analysis->occluder > 0 && analysis->refused_sampled == 0;
        stats.rows_sampled_fine += analysis->occluder == 2;
        stats.rows_sampled_unproven += analysis->sampled_unproven;
    }
    // A sampled row is already the 2 × 2 sender quadrature (sub-hemicubes): no ratio on top.
    const bool quadrature = im.options.sender_quadrature && !sampled_row;
    const double inner_sum = row.sum();
    const bool quadrature_needed = quadrature && sender_quadrature_needed(im.patches, im.options, i, row.col);
    // A ray-cast row (cast_rays): the rays' noise, no pixels, no quadrature residual.
    const bool cast = sampled_row && cast_rays > 0;
    const double pixel_delta_ff = cast                          ? 0.0
                                  : analysis->pixel_delta_ff >= 0 ? analysis->pixel_delta_ff
                                                                  : im.options.pixel_delta_ff;
    const RowErrorModel error{im.patches.scene, im.patches.scene.patches[i], pixel_delta_ff,
                              cast ? cast_rays : im.options.rays, sampled_row && !cast, quadrature};
    count_small_receivers(row, pixel_delta_ff, stats);
    // The sum's noise: pixels (or rays) moved between two receivers leave the sum as it is; only
    // the outline against the sky moves it, modelled as a receiver of the sky's share (none for a
    // row not measured: the analysis is the row).
    if (noise) noise->sky = analysis->skipped ? 0.0 : error.noise(std::max(0.0, 1.0 - inner_sum));
    const auto& exact = analysis->exact;  // (j, exact F_ij), j increasing
    double estimate = analysis->far_error;
    if (exact.empty() && !quadrature_needed) {
        ++stats.rows_untouched;
        if (error_estimate) {
            for (std::size_t a = 0; a < row.nnz(); ++a) {
                const double sigma = error.noise(row.val[a]);
                estimate += error.midpoint(row.col[a], row.val[a]) + sigma;
                if (noise) noise->add(sigma);
            }
            *error_estimate = estimate;
        }
        stats.quadrature_seconds += quadrature_watch.seconds();
        return;
    }
    if (!exact.empty()) ++stats.rows_touched;
    if (quadrature_needed) ++stats.rows_quadrature;
    stats.replaced += exact.size();
    const SenderQuadrature rule(im.patches, im.options, i, error, quadrature_needed, b.quadrature_points,
                                b.quadrature_weights);
    stats.quadrature += merge_row(row, exact, rule, error, b.merged, estimate, noise);
    if (im.options.keep_closed_rows) {
        ClosedTest test{analysis->skipped, inner_sum, analysis->far_error};
        if (analysis->measured_rays > 0) test.measured_tolerance = 2.0 / analysis->measured_rays;
        const Rebalance r = rebalance_row(b.merged.row.val, b.merged.is_exact, test);
        if (r.applied) {
            ++(r.closed ? stats.rows_closed : stats.rows_capped);
            stats.closed_scale_max_change = std::max(stats.closed_scale_max_change, std::abs(r.factor - 1.0));
            estimate += r.moved;
            // A closed row now sums to 1, as its exact row does: no sum error is left for the
            // noise to explain (the entries' share of the change is in r.moved above).
            if (r.closed && noise) noise->sky = noise->replaced_sum_sq = 0.0;
        }
    }
    if (error_estimate) *error_estimate = estimate;
    std::swap(row, b.merged.row);
    stats.quadrature_seconds += quadrature_watch.seconds();
}

}  // namespace ffcube
