// Occlusion culling for one hemicube face, on the CPU (no GL): which pieces lie wholly behind
// what a first, partial drawing of the face (the occluders) already shows, so that drawing them
// cannot change a pixel (issue 15, part 3: a hemicube in a street of a city sees a few facades,
// and the rest of the city behind them cost it as much as what it sees).
//
// Depth is the hemicube's (gl/hemicube_worker.cpp): reversed Z with an infinite far plane, so a
// point at distance d along the face's forward axis has depth near / d; larger is nearer, 0 is
// nothing drawn. Fragments exist only for d >= near (glClipControl ZERO_TO_ONE, no depth clamp:
// depth above 1 is clipped).
#pragma once

#include <algorithm>
#include <array>
#include <bit>
#include <cstdint>
#include <span>
#include <vector>

#include "ffcube/hemicube/frame.hpp"
#include "ffcube/hemicube/layout.hpp"
#include "ffcube/hemicube/piece_bvh.hpp"

namespace ffcube {

// Where a convex polygon can show on a face: the rectangle of face pixels that may hold one of
// its fragments, and the largest depth any of its points there can have. Optionally also
// half-planes in face pixel coordinates (column, row; pixel (x, y) has its centre at
// (x + 0.5, y + 0.5)) that every pixel centre it may fill satisfies: nx·col + ny·row <= c
// (c includes the one-pixel margin). Without them the rectangle alone bounds it.
struct FaceFootprint {
    static constexpr int kMaxEdges = 8;
    int x0, y0, x1, y1;  // inclusive, clamped to the viewport; x0 > x1 or y0 > y1: no pixel
    double max_depth;    // near / (the least distance along forward of the clipped polygon)
    int edges = 0;
    std::array<std::array<double, 3>, kMaxEdges> edge;  // (nx, ny, c); the first `edges` set
    // A pixel of the footprint that the query looks at first (outside the rectangle: none).
    int probe_x = -1, probe_y = -1;
    // The clipped polygon's projected vertices (column, row), for add_half_planes; none when it
    // has more than kMaxVerts.
    static constexpr int kMaxVerts = 16;
    int verts = 0;
    std::array<std::array<double, 2>, kMaxVerts> vert;  // the first `verts` set
};

// The minimum depth over any run of pixels of a row of one face's viewport, in O(1): per row a
// sparse table, level k holding the minimum of the 2^k pixels starting at each x (level 0 the
// pixels); a run [x0, x1] is the union of the two level-k runs starting at x0 and at
// x1 + 1 − 2^k, k the largest with 2^k <= its length.
class FaceDepthRows {
public:
    // depth: the whole atlas, row-major, atlas_width pixels a row, row 0 at the bottom (as
    // glReadPixels returns it); vp: the face's viewport in it.
    void build(std::span<const float> depth, int atlas_width, const AtlasViewport& vp);

    // Whether every pixel of the rectangle [x0, x1] × [y0, y1] (face pixels, inclusive, clipped
    // to the viewport) holds a depth greater than d: exactly what a scan of its pixels answers,
    // two table entries a row.
    bool covers(int x0, int y0, int x1, int y1, double d) const;
    // The same over the pixels of the footprint's rectangle whose centres (x + 0.5, y + 0.5)
    // satisfy all its half-planes: on each row they make one run (the half-planes are convex),
    // whose ends are solved from the half-planes (a centre on a half-plane's line may fall
    // either way by rounding: the lines lie a pixel outside what the polygon can fill).
    bool covers(const FaceFootprint& fp, double d) const;

    int width() const { return w_; }
    int height() const { return h_; }

private:
    bool run_covers(int y, int x0, int x1, double d) const {
        const int len = x1 - x0 + 1;
        const int k = std::bit_width(static_cast<unsigned>(len)) - 1;
        const float* t = min_.data() + static_cast<std::size_t>(k) * plane_ + static_cast<std::size_t>(y) * w_;
        return static_cast<double>(std::min(t[x0], t[x1 + 1 - (1 << k)])) > d;
    }

    int w_ = 0, h_ = 0, levels_ = 0;
    std::size_t plane_ = 0;  // w_ × h_: one level
    std::vector<float> min_;
};

// The footprint of the convex planar polygon with these corners (hemicube local frame, eye at
// the origin) on face f drawn with near plane `near`; with its edges' half-planes
// (add_half_planes) when `edges`. The polygon is first clipped
// (Sutherland–Hodgman, in the face's frame) to what can make a fragment: the near plane
// (forward·v >= near; GL clips depth above 1) and the face's frustum widened by one pixel on
// each side (pixel centres lie half a pixel inside the viewport; the widening takes the
// rasterizer's snapping and the float rounding of GL's own clipping). A polygon crossing the
// face's eye plane thus gets a bounded footprint; one wholly outside gets none (x0 > x1).
// The rectangle is the clipped polygon's projected bounding box grown by one pixel on each
// side: the rasterizer snaps vertices to a fraction of a pixel and samples pixel centres, so
// every pixel it fills lies inside. max_depth = near / the least forward distance of the
// clipped polygon's vertices (distance is linear on the polygon: its minimum is at a vertex);
// a polygon reaching the near plane gets 1, the largest depth there is, and is never culled.
FaceFootprint face_footprint(const FaceSpec& f, std::span<const Vec3> corners, double near, bool edges = true);

// Adds the half-planes of the footprint's edges, for a rectangle larger than 4 × 4 pixels
// (smaller ones gain little) with its vertices kept; false when it adds none. The perspective
// projection maps the clipped polygon (convex, planar, in front of the eye) onto the convex hull
// of its projected vertices; a filled pixel centre lies within a fraction of a pixel of it (the
// rasterizer's snapping), so within one pixel of every supporting line. Each edge's line gets
// the side and the offset that hold every projected vertex (so the half-plane holds the hull
// whatever the rounding or the orientation), then one pixel more.
bool add_half_planes(FaceFootprint& fp);

// The relative depth margin of the test (hidden_behind): a piece is culled only when its nearest
// possible depth is below (1 − kOcclusionMargin) × the occluders' least depth over its footprint.
// What it absorbs: the rasterizer interpolates depth in float from the vertices' float
// coordinates, so a fragment may lie a few float ulps (about 1e-7 each) times the triangle's
// conditioning nearer than the exact max_depth; 1e-2 leaves a factor 1e5 for that (slivers of
// aspect up to ~1e5), and a piece just 1% behind a facade is rare (what hides a piece in a city
// is a building in between, tens of percent nearer). A triangle that crosses the near plane is
// clipped by GL in float first (its new vertices lie on the near plane, at depth 1), which adds
// the same kind of rounding, relative to its clip coordinates, to that conditioning; the item
// buffers of the cities, whose ground and facade triangles cross the faces' eye planes, are
// bitwise those drawn without culling (docs/benchmarks.md).
inline constexpr double kOcclusionMargin = 1e-2;

// Whether a polygon with this footprint is hidden on the face: every pixel it may fill already
// holds a depth nearer than any of its points by the margin.
// Cheapest first: the probe pixel (a visible piece usually ends there), the rectangle, then
// (when the rectangle is not covered) the rectangle cut by the edges' half-planes, which it adds
// to fp.
bool hidden_behind(const FaceDepthRows& depth, FaceFootprint& fp);

// Per piece, the faces on which hide_hidden_nodes proved it hidden, for one hemicube (a stamp per
// piece, so that starting the next hemicube clears nothing).
class HiddenFaces {
public:
    void begin(std::size_t pieces) {
        if (stamp_.size() != pieces || ++now_ == 0) {
            stamp_.assign(pieces, 0);
            faces_.assign(pieces, 0);
            now_ = 1;
        }
    }
    std::uint8_t of(std::uint32_t g) const { return stamp_[g] == now_ ? faces_[g] : std::uint8_t{0}; }
    void add(std::uint32_t g, unsigned bits) {
        if (stamp_[g] != now_) {
            stamp_[g] = now_;
            faces_[g] = 0;
        }
        faces_[g] = static_cast<std::uint8_t>(faces_[g] | bits);
    }

private:
    std::vector<std::uint32_t> stamp_;
    std::vector<std::uint8_t> faces_;
    std::uint32_t now_ = 0;
};

// Occlusion culling by whole nodes of the pieces' hierarchy (issue 15: in a city most of what a
// face culls lies behind the first facades in whole blocks, and testing it piece by piece was a
// quarter of a city run's CPU). Walks bvh from the root with the faces in `open` (bit f: faces[f])
// and, for each face, marks in `out` every piece under a node whose box is hidden on that face
// behind depth[f] (the same test as hidden_behind, on the rectangle and depth bound of the box).
// eye, frame: the hemicube's (the pieces' corners in its local frame are what face_footprint
// gets, rounded to float). Sound for the piece test: a mark implies that hidden_behind of the
// piece's own footprint (face_footprint of its corners, from those floats) is true, because the
// box holds every corner, so the box's projection holds the piece's clipped polygon's (a/d is
// linear-fractional: its extremes over a box in front of the eye are at corners), and the box's
// least distance bounds the piece's; the float rounding of the corners (2^-24 of a coordinate)
// and of the double arithmetic is covered by widening the box by E = 2e-7 × its largest
// coordinate sum in every direction. So the pieces left out are exactly those the piece test
// leaves out: the walk only spares the tests (test OcclusionNodes.*). Returns the nodes hidden.
std::size_t hide_hidden_nodes(const PieceBvh& bvh, const std::array<FaceSpec, 5>& faces,
                              const std::array<FaceDepthRows, 5>& depth, const Vec3& eye, const HemicubeFrame& frame,
                              double near, unsigned open, HiddenFaces& out);

}  // namespace ffcube
