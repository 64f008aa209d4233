// What a hemicube draws: the mesher's pieces (Scene::grids, a face's quad or triangle drawn
// whole; the fragment shader finds the patch), prepared once per scene on the CPU and shared
// read-only by every worker. No GL here: the GL worker (src/gl) uploads these arrays as they are.
//
// Pieces meet in T-junctions where a corner of one lies inside an edge of another (a wall split
// at a height its neighbours are not, a floor of faces of different widths). Rasterized from
// different endpoints, the long edge and the short ones beside it do not cover the same pixels:
// pixel-size cracks open between them, and hemicubes see through closed walls. So each piece is
// drawn as the polygon of its corners and of the other pieces' corners that lie strictly inside
// its edges (find_edge_vertices): those T-vertices take the other piece's corner position bit
// for bit, so after the shared double → float transform both pieces' edges end at the very same
// vertices, and the rasterizer's rules for shared edges leave no gap and no overlap. The polygon
// is cut into triangles none of zero area (triangulate_boundary).
#pragma once

#include <array>
#include <cstdint>
#include <span>
#include <vector>

#include "ffcube/geometry/polygon.hpp"
#include "ffcube/hemicube/piece_bvh.hpp"
#include "ffcube/scene/scene.hpp"

namespace ffcube {

// A piece as the item shader sees it: its corners 1..3 in its plane (corner 0 at the origin; the
// GL worker gives a general quad's to every vertex slot of it, shaders/item.vert), its kind
// (3 triangle, 4 general quad: plane coordinates, inverse bilinear, 5 parallelogram), its cells
// and first patch.
struct GpuGrid {
    float q1[2], q2[2], q3[2];
    std::uint32_t count, nu, nv, first;
};
static_assert(sizeof(GpuGrid) == 40);

// The scene's pieces. Each piece owns a run of vertex slots: its corners first (count of them),
// then the T-vertices on its edges. Per slot: world position, the vertex parameter (cell
// coordinates for affine pieces, plane coordinates for general quads) and the piece index.
// Pieces that lie on a supporting plane of the whole scene, front side in: every corner of every
// piece lies on the plane's front side or on it (within `tolerance`). Let P be the intersection
// of these planes' front half-spaces and e an eye strictly inside P (in front of every plane by
// more than the tolerance). Every piece lies in P, so a ray from e leaves P once, through at most
// one of these planes: two enclosure pieces never overlap on e's screen (they meet at most along
// shared edges), both face e, and every other piece that a ray meets lies before (nearer than) the
// enclosure piece it then meets. So from e the enclosure pieces can be drawn first with no depth
// test at all, and the other pieces after them, depth-tested among themselves only, over them:
// the same picture as depth-testing everything, with less per-pixel work (llvmpipe: 20% of the
// drawing in a closed box; docs/benchmarks.md). Ties in depth: a plane that another piece lies in
// facing the other way (a plate upside down on the floor, the other side of a two-sided wall) is
// left out, since the depth test decided there; a piece lying in it facing the same way joins
// it, and the enclosure is drawn in reverse piece order, so where two of its pieces overlap the
// first piece wins, as GL_GREATER let the first drawn win an exact tie (duplicate faces keep their
// pixels; two different coplanar pieces that overlap show the first instead of z-fighting).
struct Enclosure {
    struct Plane {
        Vec3 normal{0.0};  // unit; the front side is n·x > offset
        double offset = 0;
    };
    std::vector<Plane> planes;
    std::vector<std::uint8_t> piece;  // per piece: it lies on one of planes (empty: none)
    double tolerance = 0;             // of "on the plane" and "in front", in scene units
    // The other pieces all lie in one plane (within the tolerance), and either all face one way
    // or each has a twin (a two-sided plate: a blocker, a partition, a radiation shield): from an
    // eye inside, no two of them that are drawn overlap either, but where coplanar pieces
    // overlap in their plane, so a hemicube needs no depth test at all (drawn in reverse piece
    // order, the first wins such overlaps, as with the test). True for an empty room.
    bool inner_flat = false;
    // The enclosure pieces make a closed surface: every edge (corner to corner) of one is an edge
    // of another, met the other way round, with bitwise equal corners. They then cover the whole
    // boundary of P, every direction from an eye inside shows one of them, and since GL's
    // rasterization gives a pixel centre on an edge shared by two triangles with identical
    // endpoints to exactly one of them, every pixel of the hemicube is drawn: it need not be
    // cleared first. False where a corner of one lies inside another's edge (a T-vertex), or a
    // wall is missing (an open box, a city).
    bool closed = false;
    // The eye lies in front of every plane by more than the tolerance (true when there is none).
    bool contains(const Vec3& eye) const;
};

// The enclosure of a scene's pieces: supporting planes as above, at most kMaxEnclosurePlanes of
// them (a piece on none of the kept planes is simply drawn with the depth test), found in piece
// order; pieces that are not planar within the tolerance are never enclosure pieces.
inline constexpr std::size_t kMaxEnclosurePlanes = 64;
// has_twin: per piece, as find_twins (empty: no twins).
Enclosure find_enclosure(std::span<const PatchGrid> grids, std::span<const std::uint8_t> has_twin = {});

struct ScenePieces {
    std::vector<GpuGrid> gpu;
    std::vector<Vec3> pos;             // 1 per vertex slot: world position
    std::vector<float> param;          // 2 per vertex slot
    std::vector<std::uint32_t> grid;   // 1 per vertex slot
    std::vector<std::uint32_t> info;   // 4 per vertex slot: its piece's kind, nu, nv, first patch
    std::array<bool, 6> has_kind{};    // some piece is of this kind (3, 4 or 5)
    // Every piece is one patch (a mesh read with --no-subdivide, one patch per facet): the front
    // pass's shaders then pass the patch per vertex and interpolate nothing (SINGLE_CELL in
    // shaders/item.vert), which is most of a small triangle's cost in llvmpipe's setup.
    bool single_cell = true;
    std::vector<std::uint32_t> first;  // per piece, plus one at the end: its first vertex slot
    // Per piece, plus one at the end: its range in 'tris'. An empty range means the piece is
    // drawn as its corners say: (c0, c1, c2), and (c0, c2, c3) for a quad.
    std::vector<std::uint32_t> tri_first;
    std::vector<std::uint32_t> tris;   // vertex slot triples, CCW from the front
    // Per piece: another piece has exactly its corners and faces the other way (one side of a
    // two-sided plate made of two one-sided faces). When such a piece shows its back, its twin
    // shows its front over exactly the same pixels: the back is not drawn at all, so the two
    // can never z-fight, however steeply they are seen (a depth offset could not settle that
    // without letting things behind edge-on back faces through).
    std::vector<std::uint8_t> has_twin;
    // The scene's enclosure (find_enclosure): pieces whose plane has the whole scene on its front
    // side (a convex room's walls, a city's flat ground), drawn without the depth test from an eye
    // strictly in front of every one of these planes.
    Enclosure enclosure;
    // Over the pieces' corner boxes: which pieces may lie in front of a hemicube's plane.
    PieceBvh bvh;
};

// Builds ScenePieces: plane coordinates, piece kinds, T-vertices and their triangulation, twins.
// Pieces without T-vertices keep exactly the triangles (c0, c1, c2), (c0, c2, c3).
ScenePieces prepare_pieces(std::span<const PatchGrid> grids);

// The twin pieces: every pair (a, b), a < b, of pieces with the same corner set (bitwise equal
// positions) and opposite normals (a two-sided plate of two one-sided faces).
std::vector<std::pair<std::uint32_t, std::uint32_t>> twin_pairs(std::span<const PatchGrid> grids);
// has_twin per piece: it is in one of twin_pairs.
std::vector<std::uint8_t> find_twins(std::span<const PatchGrid> grids);

// A corner of another piece strictly inside edge k (corner k → k + 1) of piece g.
struct EdgeVertex {
    std::uint32_t g, k;
    double t;            // position along the edge, 0 at corner k, 1 at corner k + 1
    std::uint32_t at;    // index into the unique corner positions
};

// How far off an edge (a → b) a corner may lie and still count as on it: 1e-6 of the edge
// (OBJ files written with 6 significant digits put a corner meant to lie inside an oblique edge
// up to ~1e-7 of the edge off it), plus a few ulps of the coordinates' magnitude, so a small
// piece far from the origin (1e5) is judged by what its coordinates can hold, not by its size
// alone.
double edge_tolerance(const Vec3& a, const Vec3& b);

// Corners of other pieces that lie on a piece's edge strictly between its endpoints (within
// edge_tolerance), for every piece edge, sorted by (piece, edge, t), each corner once per edge.
// 'corners' receives the unique corner positions, sorted; EdgeVertex::at indexes it.
std::vector<EdgeVertex> find_edge_vertices(std::span<const PatchGrid> grids, std::vector<Vec3>& corners);

// Triangulates a convex piece whose boundary b (vertex slots into pos, CCW from the front,
// starting at corner 0) has T-vertices inside some edges, appending b.size() − 2 triangles to
// tris, none of which has its three vertices on one edge of the piece. on_edges[i]: the piece
// edges (bit k: edge k) boundary vertex i lies on: two bits for a corner, one for a T-vertex.
void triangulate_boundary(const std::vector<std::uint32_t>& b, const std::vector<std::uint8_t>& on_edges,
                          const std::vector<Vec3>& pos, std::vector<std::uint32_t>& tris);

}  // namespace ffcube
