// Adaptive meshing's geometry: a scene whose chosen patches are split into elements (docs/adaptive.md).
// A patch split by s becomes s × s similar elements in its own PatchGrid (a quad: the bilinear grid
// of its corners; a triangle: the triangle grid of its corners), in the patch's place in patch
// order; a grid none of whose patches is split is kept whole, so a hemicube still draws it as one
// piece. Elements keep the patch's object and material.
#pragma once

#include <array>
#include <cstdint>
#include <span>
#include <vector>

#include "ffcube/scene/scene.hpp"

namespace ffcube {

struct RefinedScene {
    Scene scene;
    // parent[e]: the patch of the input scene that element e lies in.
    std::vector<std::uint32_t> parent;
};

// split[i] ≥ 1 for every patch i (1: kept). InternalError when sizes differ or a factor is 0.
RefinedScene refine_patches(const Scene& scene, std::span<const std::uint32_t> split);

// The mesher's hash of meshed geometry (Scene::fingerprint), for scenes built outside build_scene.
std::uint64_t scene_fingerprint(const Scene& scene);

// A patch's area, normal, centroid and size from its vertices, as the mesher fills them (mesher.cpp).
void fill_patch_geometry(Scene& scene, Patch& patch);

// The mesher's grids (scene.hpp, PatchGrid), for the mesher and refine_patches alike: append to
// `scene` the vertices, the PatchGrid and the patches of a quad c[0..3] split nu × nv along its
// bilinear map, or of a triangle c[0..2] split into k² similar triangles (upright and inverted, in
// PatchGrid's order). Each patch is a copy of `like` (object, material) with its vertices, count
// and geometry (fill_patch_geometry) set.
void append_quad_grid(Scene& scene, const std::array<Vec3, 4>& c, std::uint32_t nu, std::uint32_t nv, const Patch& like);
void append_triangle_grid(Scene& scene, const std::array<Vec3, 4>& c, std::uint32_t k, const Patch& like);

}  // namespace ffcube
