// From per-patch values (radiosity, radiance) to a mesh with values at its vertices, for drawing
// and for export. No GL: pure geometry on the CPU.
#pragma once

#include <cstdint>
#include <span>
#include <vector>

#include "ffcube/scene/scene.hpp"

namespace ffcube {

enum class Shading {
    // Every patch keeps its own value: one output vertex per patch corner, all with the patch's
    // value. What the solver computed, without interpolation.
    Flat,
    // Patch values interpolated to vertices: a vertex takes the area-weighted mean of the patches
    // that touch it within one surface (same object, normals within about 25°), so that shading is
    // continuous across a wall but a corner between two walls (or two objects) stays sharp.
    Smooth,
};

// A polygon mesh with one value per vertex.
struct ShadedMesh {
    std::vector<Vec3> positions;
    std::vector<Vec3> values;
    // Face f (one per patch, in patch order) has face_sizes[f] (3 or 4) vertices, listed CCW from
    // the front in face_indices.
    std::vector<std::uint8_t> face_sizes;
    std::vector<std::uint32_t> face_indices;
};

// patch_values[i] is patch i's value (size scene.size()). Vertices count as the same point when
// they lie within 1e-7 × scene.extent() of each other (the mesher computes a point shared by two
// grids separately on each side, so indices alone do not say it is shared).
ShadedMesh shade_patches(const Scene& scene, std::span<const Vec3> patch_values, Shading shading);

}  // namespace ffcube
