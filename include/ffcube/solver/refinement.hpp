// Where adaptive meshing refines (docs/adaptive.md): an a-posteriori indicator of how much a
// solved radiosity varies across each patch, and the marking of the patches to split. No GL: it
// reads a Scene and B.
#pragma once

#include <cstdint>
#include <span>
#include <vector>

#include "ffcube/scene/scene.hpp"

namespace ffcube {

// Luminance (the formula of render/image.hpp's luminance, which this layer cannot see) Y = 0.2126 r + 0.7152 g + 0.0722 b of an RGB radiosity (the weights of sRGB/Rec. 709).
double radiosity_luminance(const Vec3& b);

// Per patch i: half the largest luminance jump |Y_i − Y_j| to a neighbour j on the same surface (same
// object, normals within 25°, centroids no farther apart than 0.75 (size_i + size_j), which takes
// in edge and corner neighbours of the mesher's grids and of refined elements). Piecewise-constant
// B misses a linear variation by about this much at the patch's edge: the estimate of the error of
// B inside the patch. 0 for a patch without neighbours.
std::vector<double> radiosity_variation(const Scene& scene, std::span<const Vec3> radiosity);

struct RefinementChoice {
    std::vector<std::uint32_t> split;  // per patch: 1 (kept) or the split factor
    std::size_t marked = 0;            // patches split
    std::size_t candidates = 0;        // patches whose relative variation exceeds the target
    std::size_t elements_after = 0;    // patches of the refined scene
    bool budget_limited = false;       // some candidates were left for lack of budget
};

// Marks the patches to split by `factor` (≥ 2) into factor² elements: the candidates are the patches
// whose variation (radiosity_variation) exceeds target × the mean luminance of their object;
// they are taken in order of η = variation × area (the power misplaced by the constant, largest
// first; ties by index, so the choice is deterministic) until the marked ones hold `fraction` of
// the candidates' Σ η (Dörfler's bulk criterion: refinement goes where the error is, not
// everywhere it exceeds the target), and while the refined scene stays within max_elements.
RefinementChoice choose_refinement(const Scene& scene, std::span<const Vec3> radiosity, double target,
                                   std::size_t max_elements, std::uint32_t factor = 2, double fraction = 1.0);

}  // namespace ffcube
