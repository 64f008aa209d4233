// Internal to the accuracy layer. One job: the far field (docs/accuracy.md, "Far field"): the
// scene's planes with the O(1) plane-test visibility proof of a pair, and the analytic value of
// a proven pair beyond the near range with its error bound. Its cost model, which decides
// whether `auto` turns it on, is in far_field_cost.cpp.
#pragma once

#include <array>
#include <cmath>
#include <cstdint>
#include <span>
#include <string>
#include <utility>
#include <vector>

#include "accuracy/patch_set.hpp"
#include "accuracy/spatial_grid.hpp"
#include "ffcube/accuracy/near_field.hpp"

namespace ffcube::accuracy {

// How a far pair's value is integrated, by centroid distance d in sizes (the larger of the
// pair's longest edges): the exact receiver (Lambert's contour) and a 3 × 3 sender rule below
// kFarPoint3K, the point kernel cosθ_i cosθ_j / (π r²) on 3 × 3 points of each patch below
// kFarPoint2K, on 2 × 2 points of each beyond. Relative errors measured against the contour
// integral (unit squares parallel, perpendicular on a common plane, tilted): Lambert 3 × 3 ≤ 7e-6
// at 3 sizes; point 3 × 3 ≤ 3.5e-6 at 4 sizes, 1.7e-7 at 6; point 2 × 2 ≤ 1.1e-5 at 12 sizes,
// 1.4e-6 at 20. Errors fall as (h/d)⁶ and (h/d)⁴: the bounds in value() are those, with margin.
// Lambert's contour costs an atan2 per edge per point; the point kernel a few flops per pair of
// points: 9 contours cost about as much as 300 kernel evaluations. At kFarPoint1K sizes and
// beyond, one point per patch (the centroids) is enough: the midpoint rule's relative error is
// (2/3)(h/d)² for squares face to face (the offset ρ between a point of each has ⟨ρ²⟩ = h²/3 and
// the kernel falls as 1 − 2ρ²/d²; tests/accuracy/test_far_field.cpp), 1.6e-6 there; bounded by
// (h/d)².
constexpr double kFarPoint3K = 5.0;
constexpr double kFarPoint2K = 16.0;
constexpr double kFarPoint1K = 640.0;

// The least the far field can cost per row (ns): every row examines every patch
// (far_field_cost.cpp).
double far_field_cost_floor_ns(std::size_t patches);

class FarField {
public:
    // Groups the patches by plane and, in automatic mode, estimates the cost per row
    // (far_field_cost.cpp) and stays off when it is over the budget. Const afterwards.
    FarField(const PatchSet& patches, const SpatialGrid& grid, const NearFieldOptions& options);

    bool on() const { return on_; }
    // Whether row i gets far-field values: on, and i emits when only the emitting rows do
    // (NearFieldOptions::far_field_emitters).
    bool applies(std::uint32_t i) const { return on() && (only_.empty() || only_[i] != 0); }
    std::size_t rows_only() const { return only_rows_; }  // emitting rows when only they do; 0: all
    std::size_t planes() const { return on_ ? planes_.size() : 0; }  // in use by the far field
    // Whether it is on and why, in words, for the run's report and log.
    const std::string& status() const { return status_; }
    // Estimated cost of a row (ns on one core; NAN when not estimated).
    double cost_ns() const { return cost_; }
    // The planes (and the plane test, unoccluded) are kept where `auto` turned the far field off
    // for its cost: senders cut by a receiver's plane still need them (cutting_planes).
    bool has_planes() const { return !planes_.empty(); }
    // The planes (flat to the tolerance) that cut patch i: a vertex of i strictly on each side.
    // A receiver j of such a plane sees only the part of i in front of it, which the sender's
    // centre may miss altogether (docs/accuracy.md, "Senders cut by a receiver's plane").
    void cutting_planes(std::uint32_t i, std::vector<std::uint32_t>& out) const;
    std::span<const std::uint32_t> members(std::uint32_t g) const { return planes_[g].members; }
    std::uint32_t plane_of(std::uint32_t j) const { return plane_of_[j]; }  // with has_planes()

    // No plane that holds patches separates a point of i from a point of j, except where the
    // pair's hull crosses it outside the bounding box of that plane's patches. False when off.
    bool unoccluded(std::uint32_t i, std::uint32_t j) const;
    // The same for the part `front` of sender i in front of j's plane (a convex polygon of 3 to 5
    // vertices: i clipped to j's front), for a sender that j's plane cuts: the plane test with
    // that part in place of i. Costs a pass over the planes.
    bool unoccluded_front(std::span<const Vec3> front, std::uint32_t i, std::uint32_t j) const;
    // F_ij of an unoccluded facing pair at centroid distance d beyond the near range, and a
    // bound on its error (see kFarPoint3K).
    std::pair<double, double> value(std::uint32_t i, std::uint32_t j, double d) const;

    static constexpr std::size_t kMaxPlanes = 256;

private:
    // The planes of the scene's patches (unoriented; a two-sided plate's sides share one).
    struct Plane {
        Vec3 n{0.0};
        double d = 0;
        double thickness = 0;  // largest distance of a member's vertex from the plane
        Box box;               // of the members
        std::vector<std::uint32_t> members;
    };
    // A patch's 2 × 2 (index 0) or 3 × 3 (index 1) quadrature rule (3 and 9 points on a
    // triangle: geometry/quadrature.hpp).
    struct Rule {
        std::array<Vec3, 9> p{};
        std::array<double, 9> w{};
        std::uint8_t n = 0;
    };

    std::vector<std::uint8_t> only_;  // per patch, when only some rows get far-field values
    std::size_t only_rows_ = 0;
    bool group_planes();  // false: more than kMaxPlanes
    void mark_sides();
    void make_rules();
    bool section_meets(std::uint32_t i, std::uint32_t j, std::size_t g, const Box& pair) const;
    // strict: members that only touch the section do not count (unoccluded_front).
    bool section_meets(std::span<const Vec3> pi, std::span<const Vec3> pj, std::uint32_t i, std::uint32_t j, std::size_t g,
                       const Box& pair, bool strict) const;
    // far_field_cost.cpp: the cost per row of a sample of rows, and the share of them every
    // facing pair of which would be proven (rows not measured at all).
    double estimate_cost(double& complete_fraction) const;

    const PatchSet& patches_;
    const SpatialGrid& grid_;
    const NearFieldOptions& options_;
    std::vector<Plane> planes_;
    std::size_t words_ = 0;  // 64-bit words per patch in plus_bits_ / minus_bits_
    // Per patch and plane: a vertex strictly in front of / behind the plane.
    std::vector<std::uint64_t> plus_bits_, minus_bits_;
    double tol_ = 0;
    std::vector<std::array<Rule, 2>> rules_;
    std::string status_;
    double cost_ = NAN;
    double complete_ = NAN;  // estimated share of rows the far field makes complete
    bool on_ = false;
    std::vector<std::uint32_t> plane_of_;  // per patch, its plane
};

}  // namespace ffcube::accuracy
