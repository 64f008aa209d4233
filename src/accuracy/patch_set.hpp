// Internal to the accuracy layer. One job: the per-patch geometry that every piece of the
// correction reads (vertices without a triangle's repeated last one, bounding boxes and spheres,
// the tolerance of "lies in a plane" and the facing test), built once per scene.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <span>
#include <vector>

#include "ffcube/scene/scene.hpp"

namespace ffcube::accuracy {

struct Box {
    Vec3 lo{0.0}, hi{0.0};
    bool overlaps(const Box& o) const {
        return lo.x <= o.hi.x && o.lo.x <= hi.x && lo.y <= o.hi.y && o.lo.y <= hi.y && lo.z <= o.hi.z && o.lo.z <= hi.z;
    }
};

// Patch vertices without a triangle's repeated last one.
struct Poly {
    std::array<Vec3, 4> v{};
    std::size_t n = 3;
    std::span<const Vec3> span() const { return {v.data(), n}; }
};

// How far from a patch's plane a vertex of another counts as lying in it: 1e-9 of the pair's
// size (the planarity tolerance of geometry/analytic.hpp), plus the rounding of coordinates far
// from the origin (16 ulps of the largest one: a scene offset by 1e5 has its patch normals off by
// 1e-10 and its vertices off their planes by 1e-11).
double plane_tolerance(const Patch& a, const Patch& b);

struct PatchSet {
    explicit PatchSet(const Scene& scene);

    const Scene& scene;
    std::vector<Poly> polys;
    std::vector<Box> boxes;
    std::vector<double> radius;  // bounding sphere about the centroid
    std::vector<double> sizes;   // longest edges (Patch::size), in patch order
    double max_size = 0;

    std::size_t size() const { return polys.size(); }
    // Facing: some vertex of each farther than plane_tolerance in front of the other's plane (a
    // polygon within it is seen edge-on; coplanar neighbours must not count as facing).
    bool facing(std::uint32_t i, std::uint32_t j) const;
    // Whether patch i has vertices farther than plane_tolerance on both sides of j's plane.
    bool straddles(std::uint32_t i, std::uint32_t j) const;
    // Distance from point p to polygon j (its plane inside the outline, else its nearest edge).
    double distance(const Vec3& p, std::uint32_t j) const;
    // The bounding box of patches i and j together.
    Box pair_box(std::uint32_t i, std::uint32_t j) const;
};

}  // namespace ffcube::accuracy
