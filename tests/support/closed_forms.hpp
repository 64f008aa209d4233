// Independent reference values for tests of the accuracy layer: form factors between the
// axis-aligned rectangular patches of the test scenes from Howell's closed forms (C-12, C-14),
// not from the contour integral (ff_polygon_polygon) that the corrector itself calls.
#pragma once

#include <glm/common.hpp>
#include <glm/geometric.hpp>

#include <cmath>
#include <cstdint>
#include <utility>

#include "ffcube/reference/closed_forms.hpp"
#include "ffcube/geometry/analytic.hpp"
#include "ffcube/scene/scene.hpp"

namespace ffcube::test {

inline std::pair<Vec3, Vec3> patch_bounds(const Scene& s, std::uint32_t p) {
    Vec3 lo(INFINITY), hi(-INFINITY);
    const auto v = s.patch_vertices(p);
    for (std::uint32_t k = 0; k < s.patches[p].count; ++k) {
        lo = glm::min(lo, v[k]);
        hi = glm::max(hi, v[k]);
    }
    return {lo, hi};
}

// F_ij for axis-aligned rectangles in one of two arrangements, NaN for any other:
//  * in one plane: 0;
//  * both in planes z = const (parallel): 0 unless they face each other across a gap, then
//    Howell C-12 (ff_parallel_rectangles_offset);
//  * one in z = 0 facing +z ("floor") and one in y = 0 facing +y ("wall"), with the x axis as
//    their common edge line. Howell C-14 gives G(L, y, z), the exchange between the floor
//    [0,L]×[0,y] and the wall [0,L]×[0,z] (L·y·F); inclusion–exclusion in y and z gives S(L)
//    for the strips [y1,y2] and [z1,z2] over a common [0,L]; and as the kernel depends on x
//    only through x − x', offsets along x follow from
//    ∫_{a1}^{a2}∫_{b1}^{b2} = ½ [S(|b2−a1|) + S(|b1−a2|) − S(|b2−a2|) − S(|b1−a1|)].
inline double rectangle_pair_ff(const Scene& s, std::uint32_t i, std::uint32_t j) {
    const Patch& pi = s.patches[i];
    const Patch& pj = s.patches[j];
    const auto [ilo, ihi] = patch_bounds(s, i);
    const auto [jlo, jhi] = patch_bounds(s, j);
    // Coplanar: each sees the other edge-on.
    if (std::abs(glm::dot(pi.normal, pj.normal)) > 0.999 && std::abs(glm::dot(pj.centroid - pi.centroid, pi.normal)) < 1e-12)
        return 0.0;
    if (std::abs(pi.normal.z) > 0.999 && std::abs(pj.normal.z) > 0.999) {
        const double c = pj.centroid.z - pi.centroid.z;
        if (!(c * pi.normal.z > 0 && -c * pj.normal.z > 0)) return 0.0;  // coplanar, or not facing
        return ff_parallel_rectangles_offset(ilo.x, ihi.x, ilo.y, ihi.y, jlo.x, jhi.x, jlo.y, jhi.y, std::abs(c));
    }
    const bool i_floor = pi.normal.z > 0.999 && pj.normal.y > 0.999;
    const bool j_floor = pj.normal.z > 0.999 && pi.normal.y > 0.999;
    if (!i_floor && !j_floor) return NAN;
    const auto& [flo, fhi] = i_floor ? std::pair{ilo, ihi} : std::pair{jlo, jhi};
    const auto& [wlo, whi] = i_floor ? std::pair{jlo, jhi} : std::pair{ilo, ihi};
    if (flo.z != 0 || fhi.z != 0 || wlo.y != 0 || whi.y != 0 || flo.y < 0 || wlo.z < 0) return NAN;
    const auto G = [](double L, double y, double z) {
        return L > 0 && y > 0 && z > 0 ? L * y * ff_perpendicular_rectangles_common_edge(L, y, z) : 0.0;
    };
    const auto S = [&](double L) {
        L = std::abs(L);
        return G(L, fhi.y, whi.z) - G(L, flo.y, whi.z) - G(L, fhi.y, wlo.z) + G(L, flo.y, wlo.z);
    };
    const double a1 = flo.x, a2 = fhi.x, b1 = wlo.x, b2 = whi.x;
    const double exchange = 0.5 * (S(b2 - a1) + S(b1 - a2) - S(b2 - a2) - S(b1 - a1));  // A_i F_ij = A_j F_ji
    return exchange / pi.area;
}

}  // namespace ffcube::test
