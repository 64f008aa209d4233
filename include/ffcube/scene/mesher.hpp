// Meshing: ObjModel → Scene. Every face is split into patches so that no patch edge exceeds
// max_patch_edge; quads (convex, planar) become grids of quads, other faces are triangulated and
// each triangle split into m² similar triangles.
#pragma once

#include <cstddef>

#include "ffcube/scene/scene.hpp"

namespace ffcube {

struct MeshOptions {
    double max_patch_edge = 0.0;     // > 0: use it (scene units)
    std::size_t target_patches = 0;  // > 0 (and no edge given): choose the edge that gives about this many
    // Neither: default target_patches = kDefaultPatches.
    static constexpr std::size_t kDefaultPatches = 2000;
    // Refuse meshes larger than this before allocating anything (the estimate is in the message).
    std::size_t max_patches = 50'000'000;
    // false (--no-subdivide): every face is one patch, whatever its size; the edge and target
    // above must then be 0. A patch is a triangle or a convex planar quad, so a face that is
    // neither (an n-gon, a non-convex or non-planar quad) is refused, naming its line.
    bool subdivide = true;
};

// Number of patches meshing would produce with edge bound L, without building anything.
std::size_t count_patches(const ObjModel& model, double max_patch_edge);

Scene build_scene(const ObjModel& model, const MeshOptions& options);

// The memory policy of meshing: `limit` lowered to what this machine's physical memory can hold
// at the mesher's own estimate of bytes per patch (a Patch and about one vertex), so that a
// too-small --max-patch-edge is refused with the estimate instead of ending in the out-of-memory
// killer. The form-factor rows need more (docs/robustness.md), but that depends on the resolution
// and is not known before meshing.
std::size_t patch_limit_for_physical_memory(std::size_t limit);

}  // namespace ffcube
