// The scene model: what an OBJ file says (ObjModel), and the frozen, meshed Scene that every
// row provider and solver reads. Units are the file's units throughout; areas are units².
#pragma once

#include <array>
#include <cstdint>
#include <limits>
#include <memory>
#include <string>
#include <vector>

#include "ffcube/geometry/polygon.hpp"

namespace ffcube {

// Kd: diffuse reflectance ρ per RGB channel, each in [0,1].
// Ke: emitted radiosity (exitance, power per area) per RGB channel, each ≥ 0.
struct Material {
    std::string name;
    Vec3 kd{0.5, 0.5, 0.5};  // default for a missing material: grey, documented in docs/scene-format.md
    Vec3 ke{0.0, 0.0, 0.0};
};

// One polygon as written in the file, vertex order counter-clockwise seen from the front.
struct ObjFace {
    std::vector<std::uint32_t> v;  // 0-based indices into ObjModel::positions
    std::uint32_t object = 0;      // index into ObjModel::objects
    std::uint32_t material = 0;    // index into ObjModel::materials
    std::uint32_t line = 0;        // 1-based line of the 'f' statement, for messages
    std::uint64_t element = 0;     // the mesh element's id (meshes read through Gmsh), 0: none
};

// What a View3D file's control lines (C) and title (T) ask for, kept for the parts of ffcube that
// honour them (docs/scene-format.md, "View3D control keys"). From other formats: present = false.
// The smallest accuracy target (--tolerance, a .vs3's eps) ffcube accepts: a row's sum of about
// 10^4 entries in double precision, and the analytic kernels' own error (about 1e-12 relative),
// stay far below it; float storage of F (6e-8 relative) does not, for entries near 1, which the
// .ffm's documentation says.
constexpr double kMinTolerance = 1e-9;

struct View3dControls {
    bool present = false;  // the scene came from a .vs3 file
    int encl = 0;          // 1: the surfaces form an enclosure: rows are made to conserve energy (--enforce closure)
    std::uint32_t encl_line = 0;  // the C line that set encl (0: not given), for messages
    int emit = 0;          // 1: the View3D output holds Hottel's script-F (reflections included, emissivities)
    int out = 0;           // the View3D output: 0 text, 1 binary, 2 sparse text (View3D's forks: "i j F" lines)
    std::string title;     // the last T line
    // One entry per control key that ffcube does not honour: "KEY=VALUE: why" (also a warning,
    // except for the keys below that `ffcube view3d` acts on: apply_view3d_controls warns).
    std::vector<std::string> ignored;
    // Keys that only `ffcube view3d` acts on, with their lines (0: not given, or View3D's default):
    // row, col (View3D's one-row debugging run: refused there) and the forks' cut-off distance
    // maxD (a pair of surfaces whose centroids lie farther apart gets no factor: honoured there).
    int row = 0, col = 0;
    double max_distance = 0.0;  // maxD; 0: none (View3D's default, infinity)
    // eps: View3D's convergence criterion, ffcube's --tolerance when the command line gives none
    // (0: not given; View3D's default is 1e-4, ffcube's too).
    double eps = 0.0;
    std::uint32_t eps_line = 0;
    std::uint32_t row_line = 0, col_line = 0, max_distance_line = 0;
    // Masking surfaces (M): each lies on its base facing it; the covered part of the base is cut
    // out of the base's faces and the mask is an obstruction-only object (it blocks what would
    // see that part), so the matrix has no row or column for it. The View3D file gets one
    // (View3D's rules): F(mask → base) = 1, F(base → mask) = area / base area, F(base → j) the
    // rest of the base's factors over the whole base area, and the base's area whole.
    struct Mask {
        std::string name;
        std::uint32_t base_object = 0;  // the base's object (its cmb group)
        std::uint32_t position = 0;     // the View3D surface index it takes: S objects before it
        double area = 0.0;
        double emissivity = 0.0;
    };
    std::vector<Mask> masks;
};

// A parsed OBJ/MTL file before meshing. Validated: every index in range, every number finite.
struct ObjModel {
    std::string source;                 // file path (or "<built-in cornell box>") for messages
    std::vector<Vec3> positions;
    std::vector<ObjFace> faces;
    std::vector<std::string> objects;   // ObjObjectsBy: 'o' names, else 'g', else materials; else "default"
    std::vector<Material> materials;    // [0] is the default material
    std::vector<std::string> warnings;  // also printed with log_warning when loaded from the CLI
    // Counted by loaders that clean their input (STL): facets dropped as degenerate before
    // meshing, and vertex references merged into an exactly coinciding earlier vertex.
    std::size_t dropped_degenerate = 0;
    std::size_t merged_vertices = 0;
    // ObjFace::line is a facet's 1-based number (binary STL), not a line (messages say "facet N").
    bool faces_numbered = false;
    View3dControls view3d;              // a .vs3 file's control keys and title
    // The last `obstruction_objects` objects (and their faces, which come after every other
    // face) are obstruction-only (View3D's O surfaces): they block views but get no row and no
    // column. The mesher keeps them out of the Scene's patches and puts them in Scene::drawn.
    std::uint32_t obstruction_objects = 0;
};

// A patch: a planar triangle or convex quad, the unit of the form-factor matrix.
struct Patch {
    std::array<std::uint32_t, 4> v{};  // indices into Scene::positions, CCW from the front
                                       // (a triangle's v[3] repeats v[2])
    std::uint32_t count = 3;           // 3 or 4
    std::uint32_t object = 0;          // index into Scene::objects
    std::uint32_t material = 0;        // index into Scene::materials
    double area = 0.0;                 // scene units²
    Vec3 normal{0.0};                  // unit, front side
    Vec3 centroid{0.0};
    double size = 0.0;                 // longest edge, scene units
};

struct MeshStats {
    std::size_t input_faces = 0;
    std::size_t triangulated_ngons = 0;  // faces with more than 4 vertices (or non-convex quads)
    std::size_t dropped_degenerate = 0;  // zero-area faces, dropped
    std::size_t non_planar = 0;          // faces off their plane by more than 1e-6 × their size
    double max_patch_edge = 0.0;         // the L that was used
    std::string how;                     // "--max-patch-edge", "--patches N" or "default (...)"
    std::vector<std::string> warnings;   // non-planar faces (file:line), for the caller to print
};

// How the mesher split one piece of a face (a convex planar quad, or a triangle of a
// triangulated face) into patches. A renderer can draw the piece whole and find the patch of a
// point from its position in the piece:
//   quad (count 4): bilinear grid of nu × nv cells, P(u,v) = (1−u)(1−v)c0 + u(1−v)c1 + uv c2 + (1−u)v c3;
//     cell (i, j) = [i/nu, (i+1)/nu] × [j/nv, (j+1)/nv] is patch first_patch + j·nu + i.
//   triangle (count 3, k = nu = nv): P = c0 + s/k (c1 − c0) + t/k (c2 − c0); the upright cell
//     (i, j) (s ∈ [i, i+1], t ∈ [j, j+1], (s−i)+(t−j) ≤ 1) is patch first_patch + j(2k − j) + 2i,
//     the inverted cell beside it (sum > 1) the next one.
struct PatchGrid {
    std::array<Vec3, 4> corners{};  // CCW from the front; a triangle's [3] repeats [2]
    std::uint32_t count = 4;        // 4 (quad grid) or 3 (triangle grid)
    std::uint32_t nu = 1, nv = 1;   // cells along c0→c1 and c0→c3; a triangle: nu = nv = k
    std::uint32_t first_patch = 0;  // its patches are first_patch .. first_patch + cells − 1
};

// Frozen after build_scene(): row providers and solvers take it by const reference.
struct Scene {
    std::string source;
    std::vector<Vec3> positions;
    std::vector<Patch> patches;
    std::vector<PatchGrid> grids;  // every patch belongs to exactly one grid, in patch order
    std::vector<std::string> objects;
    std::vector<Material> materials;
    // Per patch, the id of the mesh element it comes from (a mesh read through Gmsh: with
    // --no-subdivide one patch per element, or per linear piece of a quadratic one); empty when
    // the faces carry no ids, or when a step after meshing (refinement) made new patches.
    std::vector<std::uint64_t> patch_elements;
    MeshStats stats;
    View3dControls view3d;  // as loaded (ObjModel::view3d)
    Vec3 bbox_min{0.0}, bbox_max{0.0};
    // What was subtracted from the file's coordinates at loading (recentre() in defects.hpp: a
    // scene far from its origin is meshed around its own centre); positions + origin are the
    // user's coordinates, which outputs that print coordinates (the patch table) show. (0,0,0)
    // for every scene near its origin.
    Vec3 origin{0.0};
    // Hash of the meshed geometry (vertex positions, patch vertices and objects). Two runs that
    // mesh the same file with the same options get the same value; materials do not enter it,
    // so a form-factor matrix stays valid when only Kd/Ke change.
    std::uint64_t fingerprint = 0;
    // Obstruction-only surfaces (View3D's O; docs/scene-format.md). When the model has them,
    // this Scene (its patches, grids, objects: every row and column of every output) holds the
    // radiating surfaces only, and `drawn` the whole scene as the row providers draw it: the
    // same patches in the same order (indices 0 .. size() − 1 agree), then the obstruction
    // patches from index `obstruction_first` on, in objects after this Scene's. The fingerprint
    // is the whole scene's. Null when there are none (then the providers draw this Scene).
    std::shared_ptr<const Scene> drawn;
    // In a scene that is drawn: patches from this index on are obstruction-only (two-sided
    // blockers whose factors are measured only to be left out, so that the sky view factor does
    // not count what they intercept); the maximum when there are none.
    std::uint32_t obstruction_first = std::numeric_limits<std::uint32_t>::max();

    std::size_t size() const { return patches.size(); }
    // The scene the row providers draw: `drawn`, or this one.
    const Scene& drawn_scene() const { return drawn ? *drawn : *this; }
    // Length of the bounding-box diagonal, scene units.
    double extent() const;
    // Positions of patch i's vertices (a triangle's [3] repeats its [2]).
    std::array<Vec3, 4> patch_vertices(std::size_t i) const;
    double total_area() const;
};

}  // namespace ffcube
