// Random polygon pairs for the property test (test_analytic_fuzz.cpp) and the libFuzzer target
// (tests/fuzz/fuzz_analytic.cpp), biased towards what breaks analytic form factors: shared
// edges and vertices, near-collinear edges, slivers, 1e-12 gaps, offsets of 1e5, scales of 1e-6,
// size ratios of 1e-4, touching perpendicular pairs. Header-only; the randomness comes from a
// Source (uniform doubles in [0, 1)), so the test draws from a seeded generator and the fuzzer
// from its bytes, through the same biasing.
#pragma once

#include "ffcube/geometry/analytic.hpp"
#include "ffcube/geometry/polygon.hpp"
#include "ffcube/geometry/tolerance.hpp"

#include <glm/geometric.hpp>

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <numbers>
#include <vector>

namespace ffcube::testing {

enum class PairKind {
    parallel_offset,     // rectangles in z = 0 (up) and z = c (down), any offsets: Howell C-12
    perpendicular_edge,  // rectangles at 90° sharing an edge: Howell C-14
    perpendicular_gap,   // the same with plate 2 lifted by a gap: C-14 by superposition
    perpendicular_vertex,  // touching at one vertex, equal edge lengths: C-14 by superposition
    separated,           // convex polygons, each wholly in front of the other, gap ≥ ½ size
    hinged,              // plates sharing an edge at an arbitrary angle (no closed form)
    stress,              // shared vertices/edges, near-collinear edges, slivers, size ratios
    count
};

inline const char* kind_name(PairKind k) {
    static const char* names[] = {"parallel_offset", "perpendicular_edge", "perpendicular_gap",
                                  "perpendicular_vertex", "separated", "hinged", "stress"};
    return names[static_cast<int>(k)];
}

struct PolygonPair {
    PairKind kind = PairKind::stress;
    std::vector<Vec3> p1, p2;
    // Parameters of the closed forms (before the transform): parallel_offset uses
    // x1 x2 y1 y2 xi1 xi2 eta1 eta2 c; the perpendicular kinds use l w h (and gap).
    double x1 = 0, x2 = 0, y1 = 0, y2 = 0, xi1 = 0, xi2 = 0, eta1 = 0, eta2 = 0, c = 0;
    double l = 0, w = 0, h = 0, gap = 0;
    // The similarity applied to both polygons: v → scale · v + offset (scale 1, offset 0 if none).
    double scale = 1.0;
    Vec3 offset{0.0};
};

inline std::vector<Vec3> rect_up(double x1, double x2, double y1, double y2, double z) {
    return {{x1, y1, z}, {x2, y1, z}, {x2, y2, z}, {x1, y2, z}};
}
inline std::vector<Vec3> rect_down(double x1, double x2, double y1, double y2, double z) {
    return {{x1, y1, z}, {x1, y2, z}, {x2, y2, z}, {x2, y1, z}};
}

// Uniform doubles in [0, 1) from `src()`; everything below is built from those.
template <class Source>
class PairGenerator {
public:
    explicit PairGenerator(Source& src) : src_(src) {}

    double uniform() {
        const double u = src_();
        return std::isfinite(u) ? std::clamp(u, 0.0, 0x1.fffffffffffffp-1) : 0.0;
    }
    double uniform(double a, double b) { return a + (b - a) * uniform(); }
    int pick(int n) { return std::min(n - 1, static_cast<int>(uniform() * n)); }
    // 10^U(lo, hi): scale-free draws.
    double log_uniform(double lo_exp, double hi_exp) { return std::pow(10.0, uniform(lo_exp, hi_exp)); }
    Vec3 unit_vector() {
        const double z = uniform(-1.0, 1.0), phi = uniform(0.0, 2.0 * std::numbers::pi);
        const double r = std::sqrt(std::max(0.0, 1.0 - z * z));
        return {r * std::cos(phi), r * std::sin(phi), z};
    }

    // A size of the biased kinds: mostly moderate, sometimes an extreme ratio.
    double side() {
        switch (pick(4)) {
            case 0: return log_uniform(-4.0, 0.0);  // ratios up to 1e4 against 1
            default: return uniform(0.05, 1.0);
        }
    }
    // A gap: exactly touching, 1e-12, small, or moderate (relative to sizes ~1).
    double gap() {
        switch (pick(4)) {
            case 0: return 1e-12;
            case 1: return log_uniform(-11.0, -3.0);
            case 2: return uniform(1e-3, 0.5);
            default: return uniform(0.05, 2.0);
        }
    }

    PolygonPair next() {
        PolygonPair p;
        p.kind = static_cast<PairKind>(pick(static_cast<int>(PairKind::count)));
        switch (p.kind) {
            case PairKind::parallel_offset: parallel(p); break;
            case PairKind::perpendicular_edge:
            case PairKind::perpendicular_gap:
            case PairKind::perpendicular_vertex: perpendicular(p); break;
            case PairKind::separated: separated(p); break;
            case PairKind::hinged: hinged(p); break;
            default: stress(p); break;
        }
        // A similarity on a third of the pairs: an offset of 1e5 (the far-off pair), a
        // scale of 1e-6 or 1e4, or both.
        // Half the pairs are also rotated (Rodrigues, random axis and angle): axis-aligned
        // rectangles have only parallel and perpendicular edge pairs, which are closed forms, and
        // rounding a rotated pair bends it off its planes.
        if (p.kind != PairKind::stress && pick(2) == 0) {
            const Vec3 k = unit_vector();
            const double angle = uniform(0.0, 2.0 * std::numbers::pi), c = std::cos(angle), s = std::sin(angle);
            const auto rotate = [&](const Vec3& v) {
                return c * v + s * glm::cross(k, v) + (1.0 - c) * glm::dot(k, v) * k;
            };
            for (Vec3& v : p.p1) v = rotate(v);
            for (Vec3& v : p.p2) v = rotate(v);
        }
        if (p.kind != PairKind::stress && pick(3) == 0) {
            const int t = pick(3);
            if (t != 1) p.offset = 1e5 * unit_vector();
            if (t != 0) p.scale = pick(2) == 0 ? 1e-6 : 1e4;
            for (Vec3& v : p.p1) v = p.scale * v + p.offset;
            for (Vec3& v : p.p2) v = p.scale * v + p.offset;
        }
        return p;
    }

private:
    void parallel(PolygonPair& p) {
        p.x1 = uniform(-1.0, 0.0);
        p.x2 = p.x1 + side();
        p.y1 = uniform(-1.0, 0.0);
        p.y2 = p.y1 + side();
        // Rectangle 2: sometimes its projection shares an edge or a corner with rectangle 1.
        switch (pick(3)) {
            case 0:
                p.xi1 = p.x2;
                p.eta1 = p.y1;
                break;
            case 1:
                p.xi1 = p.x2;
                p.eta1 = p.y2;
                break;
            default:
                p.xi1 = uniform(-1.5, 1.0);
                p.eta1 = uniform(-1.5, 1.0);
                break;
        }
        p.xi2 = p.xi1 + side();
        p.eta2 = p.eta1 + side();
        // c from 1e-9 (well above the in-plane tolerance of 1e-12 of the size) to 2.
        p.c = pick(3) == 0 ? log_uniform(-9.0, -2.0) : uniform(0.02, 2.0);
        p.p1 = rect_up(p.x1, p.x2, p.y1, p.y2, 0.0);
        p.p2 = rect_down(p.xi1, p.xi2, p.eta1, p.eta2, p.c);
    }

    // Plate 1 = [0, w] × [0, l] in z = 0 facing +z; plate 2 in the plane x = 0 facing +x.
    void perpendicular(PolygonPair& p) {
        p.l = side();
        p.w = side();
        p.h = side();
        p.p1 = rect_up(0.0, p.w, 0.0, p.l, 0.0);
        if (p.kind == PairKind::perpendicular_vertex) {
            // Over y ∈ [−l, 0], z ∈ [0, h]: touching plate 1 at the origin only.
            p.p2 = {{0, -p.l, 0}, {0, 0, 0}, {0, 0, p.h}, {0, -p.l, p.h}};
            return;
        }
        p.gap = p.kind == PairKind::perpendicular_gap ? gap() : 0.0;
        const double z0 = p.gap, z1 = p.gap + p.h;
        p.p2 = {{0, 0, z0}, {0, p.l, z0}, {0, p.l, z1}, {0, 0, z1}};
    }

    // A random convex polygon (triangle, quad or pentagon on an ellipse) of size ~`size` with
    // unit normal n, centred at c.
    std::vector<Vec3> convex(const Vec3& c, const Vec3& n, double size, double aspect) {
        const Vec3 t = glm::normalize(glm::cross(n, std::abs(n.x) < 0.9 ? Vec3(1, 0, 0) : Vec3(0, 1, 0)));
        const Vec3 b = glm::cross(n, t);
        const int k = 3 + pick(3);
        // One vertex in each of k equal sectors, at least 0.3 rad from the next sector: increasing
        // angles within one turn, so the polygon is convex and never wraps onto itself.
        const double sector = 2.0 * std::numbers::pi / k, start = uniform(0.0, sector);
        std::vector<double> angles(static_cast<std::size_t>(k));
        for (int i = 0; i < k; ++i) angles[static_cast<std::size_t>(i)] = start + i * sector + uniform(0.0, sector - 0.3);
        std::vector<Vec3> poly;
        for (double a : angles) poly.push_back(c + 0.5 * size * (std::cos(a) * t + aspect * std::sin(a) * b));
        return poly;  // counter-clockwise about n
    }

    // Each wholly in front of the other with a gap of at least half the larger size.
    void separated(PolygonPair& p) {
        for (int attempt = 0;; ++attempt) {
            const double s1 = uniform(0.2, 1.0), s2 = pick(4) == 0 ? log_uniform(-3.0, 0.0) : uniform(0.2, 1.0);
            const Vec3 d = unit_vector();
            const double dist = (0.5 + uniform(0.0, 2.5)) * std::max(s1, s2) + 0.5 * (s1 + s2);
            const Vec3 c2 = dist * d;
            // Normals within 60° of the line joining them, facing each other; after 64 misses
            // (a fuzzer's input can keep missing) exactly along it, which always qualifies.
            const double tilt = attempt < 64 ? 0.55 : 0.0;
            const Vec3 n1 = glm::normalize(d + tilt * unit_vector());
            const Vec3 n2 = glm::normalize(-d + tilt * unit_vector());
            p.p1 = convex(Vec3(0.0), n1, s1, uniform(0.3, 1.0));
            p.p2 = convex(c2, n2, s2, uniform(0.3, 1.0));
            bool ok = true;
            for (const Vec3& v : p.p2) ok = ok && glm::dot(v, n1) > 0.05 * s1;
            for (const Vec3& v : p.p1) ok = ok && glm::dot(v - c2, n2) > 0.05 * s2;
            if (ok) return;
        }
    }

    // Plates sharing the edge y ∈ [0, l] on the y axis at an interior angle α; angles near 0
    // and 180° give near-coplanar and near-folded pairs.
    void hinged(PolygonPair& p) {
        p.l = side();
        p.w = side();
        p.h = side();
        double alpha = 0.0;
        switch (pick(3)) {
            case 0: alpha = log_uniform(-6.0, -1.0); break;
            case 1: alpha = std::numbers::pi - log_uniform(-6.0, -1.0); break;
            default: alpha = uniform(0.1, 3.0); break;
        }
        const Vec3 u(std::cos(alpha), 0.0, std::sin(alpha));
        p.p1 = rect_up(0.0, p.w, 0.0, p.l, 0.0);
        p.p2 = {{0, 0, 0}, {0, p.l, 0}, Vec3(0, p.l, 0) + p.h * u, p.h * u};
        if (pick(2) == 0) p.p2 = {{0, 0, 0}, {0, p.l, 0}, Vec3(0, uniform(0.0, p.l), 0) + p.h * u};
    }

    // Triangles and quads drawn from a small pool of points so that they share vertices and
    // edges; some edges nearly collinear with or nearly parallel to another; slivers; one of the
    // pair possibly 1e-4 of the other's size; all at a random offset of up to 1e5.
    void stress(PolygonPair& p) {
        const Vec3 a(0, 0, 0), b(1, 0, 0);
        const Vec3 up = unit_vector();
        // Third vertices: a random point, a point 1e-k off the line ab (sliver), or close to a.
        // Each draw is its own statement: the order of evaluation of a constructor's arguments is
        // unspecified (g++ and clang++ differ), and a fuzzer's input must decode to the same pair
        // in the clang-built fuzzer and the g++-built tests.
        auto third = [&](const Vec3& n_hint) {
            switch (pick(3)) {
                case 0: {
                    const double x = uniform(-0.5, 1.5);
                    const double y = log_uniform(-9.0, -3.0);
                    return Vec3(x, y, 0.0) + 0.0 * n_hint;
                }
                case 1: {
                    const double r = uniform(0.05, 1.0);
                    const double x = uniform(-1, 1);
                    const double y = uniform(0.05, 1);
                    return r * glm::normalize(Vec3(x, y, 0.0));
                }
                default: {
                    const double x = uniform(-0.5, 1.5);
                    const double y = uniform(0.05, 1.0);
                    return Vec3(x, y, 0.0);
                }
            }
        };
        // Polygon 1 in z = 0, facing +z: triangle a, b, t1 (CCW as t1.y > 0).
        const Vec3 t1 = third(up);
        p.p1 = {a, b, t1};
        // Polygon 2 hinged on a shared edge (ab or a sub-edge), or on the vertex a, at angle β.
        const double beta = pick(3) == 0 ? log_uniform(-8.0, -1.0) : uniform(0.05, 3.1);
        const Vec3 u(0.0, -std::cos(beta), std::sin(beta));
        Vec3 t2 = third(up);
        const Vec3 q2 = Vec3(t2.x, 0.0, 0.0) + t2.y * u;  // t2 rotated into the tilted plane
        switch (pick(4)) {
            case 0: p.p2 = {b, a, q2}; break;                                      // shared edge
            case 1: p.p2 = {a, q2 + Vec3(uniform(-1, 1), 0, 0), q2}; break;        // shared vertex
            case 2: {                                                               // near-parallel edge
                const double tilt = log_uniform(-14.0, -8.0);
                const double g = pick(2) == 0 ? 0.0 : log_uniform(-12.0, -4.0);
                const Vec3 e0 = Vec3(uniform(-0.5, 0.5), 0.0, g), e1 = Vec3(uniform(0.6, 1.5), tilt, g);
                p.p2 = {e1, e0, e0 + u * uniform(0.01, 1.0)};
                break;
            }
            default: {                                                              // tiny next to big
                const double s = log_uniform(-4.0, -1.0);
                const double ox = uniform(0.0, 1.0);
                const Vec3 o(ox, 0.0, pick(2) == 0 ? 0.0 : 1e-12);
                p.p2 = {o + s * Vec3(1, 0, 0), o, o + s * u};
                break;
            }
        }
        if (pick(2) == 0) std::swap(p.p1, p.p2);
        // Random rotation-free offset and scale: 1e5 away, 1e-6 small, or neither.
        const int t = pick(4);
        if (t == 0 || t == 1) p.offset = 1e5 * unit_vector();
        if (t == 1 || t == 2) p.scale = 1e-6;
        for (Vec3& v : p.p1) v = p.scale * v + p.offset;
        for (Vec3& v : p.p2) v = p.scale * v + p.offset;
    }

    Source& src_;
};

// ---- the stated error of ff_polygon_polygon -----------------------------------------------

inline double perimeter(const std::vector<Vec3>& p) {
    double s = 0;
    for (std::size_t i = 0; i < p.size(); ++i) s += glm::length(p[(i + 1) % p.size()] - p[i]);
    return s;
}

// Bound on |A1 F12 − exact| in units of s² (s = the pair's longest edge: the scaled units the
// code works in), from analytic.cpp's rules. Contour path, per pair of edges (lengths lp, lq ≤ 1):
//   ≤ 4 cuts × 1e-13 lp lq   (the quadrature tolerance, halved per level: the accepted panels'
//                             tolerances sum to the cut's, Kraft's equality)
//   + 1e-14 × 3 × lq          (the noise floor, extent ≤ 3 in the contour regime)
//   + 50 ε ∫|g| ≤ 1e-14 × 45 lp lq   (the roundoff test; |ln r| ≤ 45 down to r = 1e-20)
//   + 16 ε × |terms|          (rounding of the sum; |terms| ≤ 45 lp lq)
// so ≤ 1e-12 lp lq + 3e-14 lq per pair, summed: 1e-12 P1 P2 + 3e-14 k1 P2, over 2π. The far
// field is stated to 1e-10 relative (analytic.hpp; it is 1e-14 at the distances drawn here).
inline double stated_error_area(const std::vector<Vec3>& p1, const std::vector<Vec3>& p2, double f12,
                         const AnalyticCallInfo& info) {
    const double s = std::max(polygon_max_edge(p1), polygon_max_edge(p2));
    const double P1 = perimeter(p1) / s, P2 = perimeter(p2) / s, A1 = polygon_area(p1) / (s * s);
    double e = 0.0;
    if (info.method == AnalyticCallInfo::Method::contour)
        e = (1e-12 * P1 * P2 + 3e-14 * static_cast<double>(p1.size() + 1) * P2) / (2 * std::numbers::pi);
    else if (info.method == AnalyticCallInfo::Method::far_field)
        e = 1e-10 * f12 * A1;
    // The zero method (nothing in front, edge-on within tolerance) is covered by the rounding
    // term below: moving vertices by δ changes A1 F12 by at most δ P1 P2 (2 + ln(1/δ)) / 2π.
    // Plus a fallback's own bound, and the rounding of the input coordinates: δ = 16 ε max|x| / s
    // of the pair's size (geometric_tolerance), which perturbs the contours themselves.
    const double coord = std::max(max_abs_coordinate(p1), max_abs_coordinate(p2));
    const double delta = std::max(geometric_tolerance(0.0, 0.0, coord) / s, 1e-300);
    const double pert = delta * P1 * P2 * (2.0 + std::log(1.0 / delta)) / (2 * std::numbers::pi);
    return e + pert + info.error_bound * A1;
}

}  // namespace ffcube::testing
