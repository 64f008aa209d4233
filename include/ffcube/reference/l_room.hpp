// Reference view factors of View3D's L-shaped room (examples/l_shaped_room.vs3: the manual's
// example, Pinney & Bean test 4), computed without ffcube's own machinery:
//  * pairs that see each other whole: closed forms. Parallel rectangles: Howell C-12
//    (ff_parallel_rectangles_offset). Perpendicular rectangles: Howell C-14 (sharing an edge,
//    ff_perpendicular_rectangles_common_edge) extended to any placement by view-factor algebra
//    (perpendicular_af below).
//  * pairs partly hidden from each other by the re-entrant corner: an exact point-to-polygon
//    factor (Lambert's contour formula, ff_point_polygon) to the part of the receiver that the
//    point sees, integrated over the sender by Gauss–Legendre rules on pieces where that
//    integrand is smooth (see partly_hidden_af).
// Used by the tests (tests/cli/test_view3d_l_room_cli.cpp checks it: exact to rounding) and by
// `ffcube bench` (its case l_shaped_room). Lambert's point factor is geometry's ff_point_polygon,
// a formula, not the engine's rows.
// Plan of the room: x ∈ [0,3] × y ∈ [0,1] (the x arm) ∪ x ∈ [0,1] × y ∈ [0,3] (the y arm), 3
// high. Both arms are convex boxes, so the only pairs that may be hidden are between a surface
// in the x arm beyond x = 1 and one in the y arm beyond y = 1.
#pragma once

#include <glm/geometric.hpp>

#include <array>
#include <cmath>
#include <vector>

#include "ffcube/reference/closed_forms.hpp"
#include "ffcube/geometry/analytic.hpp"
#include "ffcube/geometry/quadrature.hpp"

namespace ffcube::l_room {

// An axis-aligned rectangle: normal along `axis` (0 x, 1 y, 2 z) with sign `facing`, in the plane
// coordinate `c`, spanning [lo, hi] on the other two axes in increasing order.
struct AxisRect {
    int axis = 0;
    int facing = 1;
    double c = 0.0;
    std::array<double, 2> lo{}, hi{};
    double area() const { return (hi[0] - lo[0]) * (hi[1] - lo[1]); }
    // the other two axes, in increasing order
    std::array<int, 2> others() const { return axis == 0 ? std::array{1, 2} : axis == 1 ? std::array{0, 2} : std::array{0, 1}; }
    // the range of axis `a` (≠ axis)
    std::array<double, 2> range(int a) const {
        const auto o = others();
        const int i = o[0] == a ? 0 : 1;
        return {lo[i], hi[i]};
    }
    Vec3 normal() const {
        Vec3 n(0.0);
        n[axis] = facing;
        return n;
    }
    // corners counter-clockwise seen from the front
    std::vector<Vec3> polygon() const {
        const auto o = others();
        std::vector<Vec3> p;
        const double u[4] = {lo[0], hi[0], hi[0], lo[0]}, v[4] = {lo[1], lo[1], hi[1], hi[1]};
        for (int k = 0; k < 4; ++k) {
            Vec3 q(0.0);
            q[axis] = c;
            q[o[0]] = u[k];
            q[o[1]] = v[k];
            p.push_back(q);
        }
        // (o0, o1, axis) is a right-handed frame for axis 0 and 2 and a left-handed one for axis 1
        const bool ccw_along_plus = axis != 1;
        if (ccw_along_plus != (facing > 0)) std::swap(p[1], p[3]);
        return p;
    }
};

// A F for two perpendicular rectangles facing each other (the concave corner of the two planes),
// placed anywhere: C-14 gives Φ(L; w, h) = L w F for rectangles sharing an edge of length L (widths
// w and h away from it). A F is additive in either rectangle, so a rectangle at distances [s0, s1]
// from the common line is [0, s1] minus [0, s0]; and along the line the kernel depends only on
// the difference of the two positions and is even, so for intervals α, β along it
//   A F(α, β) = ½ [Φ(|a1−b0|) − Φ(|a1−b1|) − Φ(|a0−b0|) + Φ(|a0−b1|)]
// (the double integral of k(x − y) is H(a1−b0) − H(a1−b1) − H(a0−b0) + H(a0−b1) with H'' = k, and
// the aligned case [0, L]² gives H(d) = H(0) + Φ(|d|)/2).
inline double perpendicular_phi(double l, double w, double h) {
    if (l <= 0.0 || w <= 0.0 || h <= 0.0) return 0.0;
    return l * w * ff_perpendicular_rectangles_common_edge(l, w, h);
}
inline double perpendicular_af(std::array<double, 2> s, std::array<double, 2> t, std::array<double, 2> a,
                               std::array<double, 2> b) {
    double sum = 0.0;
    for (int i = 0; i < 2; ++i)
        for (int j = 0; j < 2; ++j) {
            const double sign = (i == 1 ? 1.0 : -1.0) * (j == 1 ? 1.0 : -1.0);
            const double w = s[i], h = t[j];
            const double along = 0.5 * (perpendicular_phi(std::abs(a[1] - b[0]), w, h) - perpendicular_phi(std::abs(a[1] - b[1]), w, h) -
                                        perpendicular_phi(std::abs(a[0] - b[0]), w, h) + perpendicular_phi(std::abs(a[0] - b[1]), w, h));
            sum += sign * along;
        }
    return sum;
}

// F(r1 → r2) for rectangles that see each other whole (no occluder between them): 0 when either
// lies behind the other's plane or both are in one plane.
inline double unhidden_factor(const AxisRect& r1, const AxisRect& r2) {
    if (r1.axis == r2.axis) {
        const double d = r2.c - r1.c;
        if (d * r1.facing <= 0.0 || -d * r2.facing <= 0.0) return 0.0;
        return ff_parallel_rectangles_offset(r1.lo[0], r1.hi[0], r1.lo[1], r1.hi[1], r2.lo[0], r2.hi[0], r2.lo[1], r2.hi[1],
                                             std::abs(d));
    }
    const int m = 3 - r1.axis - r2.axis;  // the common line runs along axis m
    const auto p = r1.range(r2.axis);     // where r1 lies across r2's plane
    const auto q = r2.range(r1.axis);
    // each must lie wholly in front of the other (touching the common line at most)
    const bool r2_in_front = (q[0] - r1.c) * r1.facing >= 0.0 && (q[1] - r1.c) * r1.facing >= 0.0;
    const bool r1_in_front = (p[0] - r2.c) * r2.facing >= 0.0 && (p[1] - r2.c) * r2.facing >= 0.0;
    if (!r2_in_front || !r1_in_front) return 0.0;
    const std::array<double, 2> s = {std::min(std::abs(p[0] - r2.c), std::abs(p[1] - r2.c)),
                                     std::max(std::abs(p[0] - r2.c), std::abs(p[1] - r2.c))};
    const std::array<double, 2> t = {std::min(std::abs(q[0] - r1.c), std::abs(q[1] - r1.c)),
                                     std::max(std::abs(q[0] - r1.c), std::abs(q[1] - r1.c))};
    return perpendicular_af(s, t, r1.range(m), r2.range(m)) / r1.area();
}

// The part of a convex polygon on the side n · (q − o) ≥ 0 of a plane (Sutherland–Hodgman).
inline std::vector<Vec3> clip_keep(const std::vector<Vec3>& poly, const Vec3& o, const Vec3& n) {
    std::vector<Vec3> out;
    for (std::size_t k = 0; k < poly.size(); ++k) {
        const Vec3& a = poly[k];
        const Vec3& b = poly[(k + 1) % poly.size()];
        const double da = glm::dot(n, a - o), db = glm::dot(n, b - o);
        if (da >= 0.0) out.push_back(a);
        if ((da >= 0.0) != (db >= 0.0)) out.push_back(a + (b - a) * (da / (da - db)));
    }
    return out;
}

// A point P of the x arm (plan x ≥ 1, y ≤ 1) sees a point Q of the y arm (x ≤ 1, y ≥ 1) exactly
// when the segment PQ crosses the plane x = y within the room's corner square, i.e. when Q's
// plan position lies on the origin's side of the vertical plane through P and the re-entrant
// corner line x = y = 1 (the plane's side is a function of P's plan position only). So
// the visible part of B from P is B clipped by that plane, and P's factor to it is Lambert's.
inline double point_to_visible_part(const Vec3& p, const Vec3& n, const AxisRect& b) {
    const std::vector<Vec3> poly = b.polygon();
    if (glm::dot(b.normal(), p - poly[0]) <= 0.0) return 0.0;  // behind B: one-sided
    const Vec3 corner(1.0, 1.0, 0.0);
    const Vec3 d(p.x - 1.0, p.y - 1.0, 0.0);
    Vec3 plane_n(-d.y, d.x, 0.0);
    if (glm::dot(plane_n, Vec3(0.0) - corner) < 0.0) plane_n = -plane_n;
    const std::vector<Vec3> visible = clip_keep(poly, corner, plane_n);
    if (visible.size() < 3 || polygon_area(visible) <= 0.0) return 0.0;
    return ff_point_polygon(p, n, visible);
}

// A F(A → B) for A in the x arm beyond x = 1, B in the y arm beyond y = 1. The integrand of
// point_to_visible_part is smooth (analytic) over A except where the clipping plane passes a
// corner of B: in plan, on lines through the re-entrant corner (1, 1) and B's corners, which in
// the x arm is the line y = 3 − 2x through (1, 1) and (1.5, 0) (aimed at (0, 3); the other corners
// give the arm's own edges x = 1 and y = 1). The pieces: a wall of the x arm is split where its
// plan meets that line, and n × n Gauss–Legendre points go on each part; the floor and ceiling
// part [1,3] × [0,1] is cut into three triangles with their apex at (1, 1) (the plane through the
// corner is then a smooth function of the angle about the apex: collapsed (Duffy) n × n rule).
inline double partly_hidden_af(const AxisRect& a, const AxisRect& b, int n) {
    const GaussRule g = gauss_legendre(n);
    const Vec3 na = a.normal();
    double af = 0.0;
    auto at01 = [&](int k) { return 0.5 * (g.x[static_cast<std::size_t>(k)] + 1.0); };
    auto w01 = [&](int k) { return 0.5 * g.w[static_cast<std::size_t>(k)]; };
    if (a.axis == 2) {
        const Vec3 apex(1.0, 1.0, a.c);
        const std::array<std::array<Vec3, 2>, 3> fans = {{{Vec3(1.0, 0.0, a.c), Vec3(1.5, 0.0, a.c)},
                                                         {Vec3(1.5, 0.0, a.c), Vec3(3.0, 0.0, a.c)},
                                                         {Vec3(3.0, 0.0, a.c), Vec3(3.0, 1.0, a.c)}}};
        for (const auto& fan : fans) {
            const double twice_area = glm::length(glm::cross(fan[0] - apex, fan[1] - apex));
            for (int i = 0; i < n; ++i)
                for (int j = 0; j < n; ++j) {
                    const double u = at01(i), v = at01(j);
                    const Vec3 p = apex + u * ((1.0 - v) * (fan[0] - apex) + v * (fan[1] - apex));
                    af += w01(i) * w01(j) * u * twice_area * point_to_visible_part(p, na, b);
                }
        }
        return af;
    }
    // a wall: its plan runs along axis h (x or y), its height along z
    const int h = a.axis == 0 ? 1 : 0;
    const auto run = a.range(h);
    const auto zr = a.range(2);
    std::vector<double> cuts = {run[0], run[1]};
    if (a.axis == 1) {  // a wall y = c: the line y = 3 − 2x meets it at x = (3 − c)/2
        const double x = (3.0 - a.c) / 2.0;
        if (x > run[0] && x < run[1]) cuts.insert(cuts.begin() + 1, x);
    } else {  // a wall x = c: at y = 3 − 2c
        const double y = 3.0 - 2.0 * a.c;
        if (y > run[0] && y < run[1]) cuts.insert(cuts.begin() + 1, y);
    }
    for (std::size_t piece = 0; piece + 1 < cuts.size(); ++piece) {
        const double s0 = cuts[piece], s1 = cuts[piece + 1];
        for (int i = 0; i < n; ++i)
            for (int j = 0; j < n; ++j) {
                Vec3 p(0.0);
                p[a.axis] = a.c;
                p[h] = s0 + (s1 - s0) * at01(i);
                p[2] = zr[0] + (zr[1] - zr[0]) * at01(j);
                af += w01(i) * w01(j) * (s1 - s0) * (zr[1] - zr[0]) * point_to_visible_part(p, na, b);
            }
    }
    return af;
}

// The room's surfaces as in examples/l_shaped_room.vs3 (S 1 … S 12), each as the parts that lie
// in the corner square, the x arm beyond x = 1 and the y arm beyond y = 1.
enum class Arm { corner, x, y };
struct RoomPart {
    int surface = 0;  // 0-based S number
    Arm arm = Arm::corner;
    AxisRect rect;
};
inline std::vector<RoomPart> l_room_parts() {
    auto r = [](int axis, int facing, double c, double lo0, double hi0, double lo1, double hi1) {
        return AxisRect{axis, facing, c, {lo0, lo1}, {hi0, hi1}};
    };
    return {
        {0, Arm::corner, r(1, +1, 0.0, 0.0, 1.0, 0.0, 3.0)},  // srf-1: y = 0, x ∈ [0,3]
        {0, Arm::x, r(1, +1, 0.0, 1.0, 3.0, 0.0, 3.0)},
        {1, Arm::x, r(0, -1, 3.0, 0.0, 1.0, 0.0, 3.0)},       // srf-2: x = 3
        {2, Arm::x, r(1, -1, 1.0, 1.0, 3.0, 0.0, 3.0)},       // srf-3: y = 1, x ∈ [1,3]
        {3, Arm::y, r(0, -1, 1.0, 1.0, 3.0, 0.0, 3.0)},       // srf-4: x = 1, y ∈ [1,3]
        {4, Arm::y, r(1, -1, 3.0, 0.0, 1.0, 0.0, 3.0)},       // srf-5: y = 3
        {5, Arm::corner, r(0, +1, 0.0, 0.0, 1.0, 0.0, 3.0)},  // srf-6: x = 0, y ∈ [0,3]
        {5, Arm::y, r(0, +1, 0.0, 1.0, 3.0, 0.0, 3.0)},
        {6, Arm::corner, r(2, -1, 3.0, 0.0, 1.0, 0.0, 1.0)},  // srf-7: ceiling over the corner
        {7, Arm::corner, r(2, +1, 0.0, 0.0, 1.0, 0.0, 1.0)},  // srf-8: floor of the corner
        {8, Arm::y, r(2, -1, 3.0, 0.0, 1.0, 1.0, 3.0)},       // srf-7b
        {9, Arm::x, r(2, -1, 3.0, 1.0, 3.0, 0.0, 1.0)},       // srf-7c
        {10, Arm::y, r(2, +1, 0.0, 0.0, 1.0, 1.0, 3.0)},      // srf-8b
        {11, Arm::x, r(2, +1, 0.0, 1.0, 3.0, 0.0, 1.0)},      // srf-8c
    };
}

// The 12 × 12 matrix F(S i → S j) with `n` Gauss points per direction on the hidden pairs.
inline std::vector<std::vector<double>> l_room_reference(int n) {
    const std::vector<RoomPart> parts = l_room_parts();
    std::vector<double> area(12, 0.0);
    for (const RoomPart& p : parts) area[static_cast<std::size_t>(p.surface)] += p.rect.area();
    std::vector<std::vector<double>> af(12, std::vector<double>(12, 0.0));
    for (const RoomPart& p : parts)
        for (const RoomPart& q : parts) {
            if (p.surface == q.surface) continue;
            double v = 0.0;
            if (p.arm == Arm::x && q.arm == Arm::y)
                v = partly_hidden_af(p.rect, q.rect, n);
            else if (p.arm == Arm::y && q.arm == Arm::x)
                v = partly_hidden_af(q.rect, p.rect, n);  // reciprocity: A_p F(p→q) = A_q F(q→p)
            else
                v = p.rect.area() * unhidden_factor(p.rect, q.rect);
            af[static_cast<std::size_t>(p.surface)][static_cast<std::size_t>(q.surface)] += v;
        }
    for (std::size_t i = 0; i < 12; ++i)
        for (std::size_t j = 0; j < 12; ++j) af[i][j] /= area[i];
    return af;
}

}  // namespace ffcube::l_room
