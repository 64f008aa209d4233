// Patch corners that are one point of one surface (smooth shading, and the smooth reconstruction
// of a piecewise-constant field that adaptive meshing's error estimate compares patches with).
#pragma once

#include <cstdint>
#include <span>
#include <vector>

#include "ffcube/scene/scene.hpp"

namespace ffcube {

// Corners at one point (within 1e-7 × scene.extent(): the mesher computes a point shared by two
// grids separately on each side, so indices alone do not say it is shared) of patches of one
// object whose normals are within acos(same_surface_cos) of the first such patch's form one vertex.
struct SurfaceVertices {
    std::vector<Vec3> positions;               // one per vertex
    std::vector<std::uint32_t> corner_vertex;  // per patch corner, patches in order, p.count each
    std::vector<std::uint32_t> first_corner;   // per patch: its first entry in corner_vertex
};
SurfaceVertices surface_vertices(const Scene& scene, double same_surface_cos);

// Per vertex: Σ A_i v_i / Σ A_i over the patches i with a corner at it.
std::vector<Vec3> vertex_average(const Scene& scene, const SurfaceVertices& vertices, std::span<const Vec3> patch_values);

}  // namespace ffcube
