// What the viewer draws, computed on the CPU (no GL): a triangle mesh with one vertex per patch
// corner (so a patch can have its own colour), the patch outlines, the groups of corners that
// smooth shading averages, and the colours of each display mode.
#pragma once

#include <cstdint>
#include <span>
#include <vector>

#include "ffcube/formfactor/sparse.hpp"
#include "ffcube/scene/scene.hpp"

namespace ffcube {

struct DisplayMesh {
    std::vector<float> positions;         // xyz per vertex; patch p owns vertices first_vertex[p] ..
    std::vector<std::uint32_t> patch;     // patch index per vertex
    std::vector<std::uint32_t> first_vertex;  // per patch, plus one past the end (size N + 1)
    std::vector<std::uint32_t> triangles;     // 3 indices per triangle, CCW from the front
    std::vector<std::uint32_t> lines;         // 2 indices per patch edge; patch p's edges are
    std::vector<std::uint32_t> first_line;    // lines[first_line[p] .. first_line[p + 1]) (size N + 1)
    // Smooth shading: the colour at vertex v is the area-weighted mean over the patches
    // smooth_patch[smooth_first[v] .. smooth_first[v + 1]): the patches with a corner at the same
    // point (to 1e-7 of the scene's extent), the same object and material, and a normal within
    // 10° (so colours do not bleed across creases or between differently coloured surfaces).
    std::vector<std::uint32_t> smooth_first;
    std::vector<std::uint32_t> smooth_patch;
    // The wireframe (W), split by where an edge lies when the scene's patches are elements of an
    // adaptive refinement (build_display_mesh's origin): 2 indices into the vertices per edge.
    // element_lines: the edges inside a patch of the starting mesh (an edge shared with an
    // element of the same patch: a 2 × 2 split's inner cross, drawn once per element, so twice);
    // patch_lines: every other edge (the starting patches' outlines). Without an origin every
    // edge is a patch edge.
    std::vector<std::uint32_t> patch_lines;
    std::vector<std::uint32_t> element_lines;

    std::size_t vertex_count() const { return patch.size(); }
};

// View3D's obstruction-only O surfaces (Scene::drawn's patches from obstruction_first on): they
// block views but have no row, no column and no radiosity, so the viewer draws them apart from
// DisplayMesh (whose colours are per radiating patch): one neutral colour, translucent, from both
// sides, with their outlines in wireframe mode. Empty for a scene without them.
struct ObstructionMesh {
    std::vector<float> positions;          // xyz per vertex
    std::vector<std::uint32_t> triangles;  // 3 indices per triangle
    std::vector<std::uint32_t> lines;      // 2 indices per edge
    std::size_t patches = 0;               // obstruction-only patches drawn (a back-to-back pair once)
};
ObstructionMesh build_obstruction_mesh(const Scene& scene);

// origin (empty, or one per patch of `scene`): the patch of the starting mesh each patch (element)
// lies in, as AdaptiveResult::origin; it only sorts the wireframe's edges (see DisplayMesh).
DisplayMesh build_display_mesh(const Scene& scene, std::span<const std::uint32_t> origin = {});

// RGB per vertex (3 floats each) from a value per patch: every corner gets its patch's value.
void flat_colors(const DisplayMesh& mesh, std::span<const Vec3> per_patch, std::vector<float>& out);
// RGB per vertex: the area-weighted mean of the vertex's smoothing group (see DisplayMesh).
void smooth_colors(const DisplayMesh& mesh, const Scene& scene, std::span<const Vec3> per_patch, std::vector<float>& out);

// Display colours (already in [0,1], shown as they are) of patch i's form-factor row F[i][·]:
// patch j is coloured by its form-factor density F[i][j] / A_j (it does not depend on how finely
// j is meshed), relative to the row's largest density on a logarithmic ramp over three decades;
// j with F[i][j] = 0 gets kNoContribution, i itself kPicked.
std::vector<Vec3> row_heat_map(const Scene& scene, std::uint32_t i, const SparseRow& row);
// The ramp: t = 0 (1/1000 of the largest density or less) dark violet, through red and orange,
// to t = 1 pale yellow; luminance increases with t.
Vec3 heat_color(double t);
// Exact in 8 bits (multiples of 1/255) so that tests can find them in a screenshot.
inline const Vec3 kNoContribution{40.0 / 255.0, 60.0 / 255.0, 80.0 / 255.0};
inline const Vec3 kPicked{0.0, 1.0, 1.0};
// Wireframe colours, exact in 8 bits: the starting patches' outlines bright amber, the element
// edges inside them dim blue (a split patch shows its 2 × 2 children inside an amber outline).
inline const Vec3 kPatchEdge{1.0, 200.0 / 255.0, 0.0};
inline const Vec3 kElementEdge{0.0, 90.0 / 255.0, 160.0 / 255.0};

// Obstruction-only surfaces: kObstruction blended over what lies behind with kObstructionAlpha
// (a pale blue-grey glass, whatever the exposure: it is not radiosity), outlines (wireframe)
// opaque. Exact in 8 bits.
inline const Vec3 kObstruction{150.0 / 255.0, 170.0 / 255.0, 190.0 / 255.0};
inline constexpr float kObstructionAlpha = 0.375f;

// RGBA8 (R in the low byte) for a hemicube item-buffer value: 0 (nothing) black, 0xFFFFFFFF (a
// back face) dark grey, 1 + patch index a bright colour from a hash of the index, so that
// neighbouring patches differ.
std::uint32_t item_color(std::uint32_t item);

}  // namespace ffcube
