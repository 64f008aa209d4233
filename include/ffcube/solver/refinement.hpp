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

// Per patch i: the mean over the patch of the smooth reconstruction of B minus B_i, per channel. The
// reconstruction interpolates vertex values linearly, a vertex taking the area-weighted mean of the
// patches of one surface (scene/surface_vertices.hpp, normals within 25°) with a corner at it, so the
// patch mean is the mean of its corners' values. Zero where B is constant; for a smooth B sampled
// at the centroids of a uniform square grid it is h²/4 ∇²B inside a surface (docs/adaptive.md,
// "The estimator"); where B jumps across a patch it is of the size of the jump, which a centroid value
// counts on one side only.
std::vector<Vec3> reconstruction_defect(const Scene& scene, std::span<const Vec3> radiosity);

// Per patch i, per channel: the estimated B_i − (mean of B over patch i), from a quadratic fitted by
// least squares to the values of i's neighbours on its surface (those of radiosity_variation; at
// least 5, not on a line) about B_i: −½ tr(H M_i), H the fit's Hessian, M_i the patch's second
// moments about its centroid over its area. A centroid value (a hemicube at the centre) misses the
// patch mean by that much where B is smooth: h²/24 ∇²B for a square of side h. 0 for patches with
// too few neighbours; `fitted` (may be null) counts the others.
std::vector<Vec3> centroid_defect(const Scene& scene, std::span<const Vec3> radiosity, std::size_t* fitted = nullptr);

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
// With `objects` (one flag per object of the scene; empty: every object), only the flagged objects'
// patches are candidates, and the bulk criterion holds per object (each flagged object's marked
// patches hold `fraction` of its own candidates' Σ η), so refinement goes to every object whose
// estimated error is over the target, not only to the one with the largest jumps.
RefinementChoice choose_refinement(const Scene& scene, std::span<const Vec3> radiosity, double target,
                                   std::size_t max_elements, std::uint32_t factor = 2, double fraction = 1.0,
                                   const std::vector<bool>& objects = {});

}  // namespace ffcube
