// Brute-force visibility for tests of the accuracy layer's occlusion proofs: random points on
// patches and an independent segment–polygon crossing test.
#pragma once

#include <glm/geometric.hpp>

#include <cstdint>
#include <random>
#include <vector>

#include "ffcube/scene/scene.hpp"

namespace ffcube::test {

// Deterministic uniform [0, 1) from a fixed-seed engine (own conversion: the same numbers with
// any standard library).
struct Rng {
    std::mt19937_64 e;
    explicit Rng(std::uint64_t seed) : e(seed) {}
    double operator()() { return static_cast<double>(e() >> 11) * 0x1.0p-53; }
    double operator()(double lo, double hi) { return lo + (hi - lo) * (*this)(); }
};

// A random point of patch j: bilinear (u, v) on a quad (inside a convex quad), folded
// barycentric on a triangle. Not area-uniform on a quad; any distribution with full support
// will do for finding blocked segments.
inline Vec3 random_point(const Scene& s, std::uint32_t j, Rng& rng) {
    const auto v = s.patch_vertices(j);
    double u = rng(), w = rng();
    if (s.patches[j].count == 4)
        return (1 - u) * (1 - w) * v[0] + u * (1 - w) * v[1] + u * w * v[2] + (1 - u) * w * v[3];
    if (u + w > 1) {
        u = 1 - u;
        w = 1 - w;
    }
    return v[0] + u * (v[1] - v[0]) + w * (v[2] - v[0]);
}

// The vertices of patch j (without a triangle's repeated last one).
inline std::vector<Vec3> patch_vertex_list(const Scene& s, std::uint32_t j) {
    const auto v = s.patch_vertices(j);
    return {v.begin(), v.begin() + s.patches[j].count};
}

// A patch for the segment test: its vertices and Newell's unit normal (which follows the vertex
// order, so the inside is left of every edge seen from the front).
struct TestPoly {
    std::vector<Vec3> v;
    Vec3 n{0.0};
};

inline TestPoly test_poly(const Scene& s, std::uint32_t j) {
    TestPoly q{patch_vertex_list(s, j), Vec3(0.0)};
    for (std::size_t k = 0; k < q.v.size(); ++k) {
        const Vec3& p = q.v[k];
        const Vec3& r = q.v[(k + 1) % q.v.size()];
        q.n += Vec3((p.y - r.y) * (p.z + r.z), (p.z - r.z) * (p.x + r.x), (p.x - r.x) * (p.y + r.y));
    }
    q.n = glm::normalize(q.n);
    return q;
}

// Whether segment a→b passes through the interior of the planar convex polygon q: its ends lie
// strictly on opposite sides of q's plane (by more than eps), the crossing is not within a
// relative 1e-9 of either end, and the crossing point is more than eps inside every edge.
// Touching (an end in the plane, a segment in the plane, a crossing on an edge) is not blocking,
// as the header documents: such segments are a set of measure zero.
inline bool crosses_interior(const Vec3& a, const Vec3& b, const TestPoly& q, double eps) {
    const double da = glm::dot(q.n, a - q.v[0]), db = glm::dot(q.n, b - q.v[0]);
    if (!((da > eps && db < -eps) || (da < -eps && db > eps))) return false;
    const double t = da / (da - db);
    if (!(t > 1e-9 && t < 1 - 1e-9)) return false;
    const Vec3 x = a + t * (b - a);
    for (std::size_t k = 0; k < q.v.size(); ++k) {
        const Vec3 e = q.v[(k + 1) % q.v.size()] - q.v[k];
        if (!(glm::dot(glm::cross(e, x - q.v[k]), q.n) / glm::length(e) > eps)) return false;
    }
    return true;
}

}  // namespace ffcube::test
