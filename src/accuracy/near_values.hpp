// Internal to the accuracy layer. One job: the value of one near pair proven unoccluded
// (F_ij, the area-to-area form factor), from the contour integral or, for pairs whose bounding
// spheres are well apart, a 6 × 6 Gauss rule on the smaller patch.
#pragma once

#include <span>
#include <vector>

#include <glm/geometric.hpp>

#include "accuracy/patch_set.hpp"

namespace ffcube::accuracy {

// Reused across calls (no heap allocation once grown; ff_polygon_polygon's own work aside).
struct NearValueScratch {
    std::vector<Vec3> a_front, b_front;  // each patch clipped to the other's front
    std::vector<Vec3> points;            // the quadrature rule of a clipped patch
    std::vector<double> weights;
};

// Sutherland–Hodgman: the part of `in` where dot(v − o, m) ≥ 0 (the part of a patch in front
// of another's plane, which alone exchanges radiation with it), its vertices handed to emit in
// order (at most in.size() + 1 of them); clip_front collects them.
template <class Emit>
void clip_front_each(std::span<const Vec3> in, const Vec3& o, const Vec3& m, Emit&& emit) {
    const std::size_t k = in.size();
    for (std::size_t e = 0; e < k; ++e) {
        const Vec3 &a = in[e], &b = in[(e + 1) % k];
        const double da = glm::dot(a - o, m), db = glm::dot(b - o, m);
        if (da >= 0) emit(a);
        if ((da > 0 && db < 0) || (da < 0 && db > 0)) emit(a + (b - a) * (da / (da - db)));
    }
}
void clip_front(std::span<const Vec3> in, const Vec3& o, const Vec3& m, std::vector<Vec3>& out);

// ff_polygon_polygon for two facing patches, with the vertices of each that lie within
// plane_tolerance of the other's plane moved to that distance in front of it (rounding leaves
// such vertices a hair behind the plane, and the contour integral's adaptive quadrature of the
// sliver so clipped never returns). The move changes F by O(1e-9) relative.
double exact_ff(const Poly& a, const Patch& pa, const Poly& b, const Patch& pb);

// Points of the sender rule for separated near pairs (separated_ff): 6 × 6 Gauss.
constexpr int kSeparatedRule = 6;
// The separated rule's error bound, relative (measured worst 3.6e-10 over 3,000 random pairs).
constexpr double kSeparatedRelativeError = 1e-9;

// F_ij for a facing pair whose bounding spheres are at least 2 radii of the smaller one apart:
// each patch clipped to the front of the other's plane, Lambert's formula from the points of a
// 6 × 6 Gauss rule on the smaller clipped patch (fan triangles when clipping made it a
// pentagon) to the other; reciprocity gives F_ij from whichever side was integrated.
double separated_ff(const Poly& a, const Patch& pa, double ra, const Poly& b, const Patch& pb, double rb,
                    NearValueScratch& scratch);

}  // namespace ffcube::accuracy
