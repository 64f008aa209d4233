// Occlusion culling for one hemicube face, on the CPU (no GL): which pieces lie wholly behind
// what a first, partial drawing of the face (the occluders) already shows, so that drawing them
// cannot change a pixel (issue 15, part 3: a hemicube in a street of a city sees a few facades,
// and the rest of the city behind them cost it as much as what it sees).
//
// Depth is the hemicube's (gl/hemicube_worker.cpp): reversed Z with an infinite far plane, so a
// point at distance d along the face's forward axis has depth near / d; larger is nearer, 0 is
// nothing drawn.
#pragma once

#include <cstdint>
#include <optional>
#include <span>
#include <vector>

#include "ffcube/hemicube/layout.hpp"

namespace ffcube {

// Minimum depth per tile of kTile × kTile pixels of one face's viewport.
class FaceDepthTiles {
public:
    static constexpr int kTile = 8;

    // depth: the whole atlas, row-major, atlas_width pixels a row, row 0 at the bottom (as
    // glReadPixels returns it); vp: the face's viewport in it.
    void build(std::span<const float> depth, int atlas_width, const AtlasViewport& vp);

    // Whether every pixel of the rectangle [x0, x1] × [y0, y1] (face pixels, inclusive, within
    // the viewport) holds a depth greater than d. Looks at the minima of the tiles the rectangle
    // meets: a superset of its pixels, so true is never wrong.
    bool covers(int x0, int y0, int x1, int y1, double d) const;

private:
    int tiles_x_ = 0, tiles_y_ = 0;
    std::vector<float> min_;
};

// Where a convex polygon can show on a face: the rectangle of face pixels that may hold one of
// its fragments, and the largest depth any of its points can have.
struct FaceFootprint {
    int x0, y0, x1, y1;  // inclusive, clamped to the viewport
    double max_depth;    // near / (the least distance along forward of its corners)
};

// The footprint of the polygon with these corners (hemicube local frame, eye at the origin) on
// face f drawn with near plane `near`; nullopt when a corner lies less than 1e-6 of its distance
// from the eye in front of the face's eye plane, or behind it (its projection is unbounded: no
// footprint, never culled). The rectangle is the projected corners' bounding box grown by one
// pixel on each side: the rasterizer snaps vertices to a fraction of a pixel and samples pixel
// centres, so every pixel it fills lies inside. A rectangle that misses the viewport comes back
// with x0 > x1 or y0 > y1.
std::optional<FaceFootprint> face_footprint(const FaceSpec& f, std::span<const Vec3> corners, double near);

// The relative depth margin of the test (hidden_behind): a piece is culled only when its nearest
// possible depth is below (1 − kOcclusionMargin) × the occluders' least depth over its footprint.
// What it absorbs: the rasterizer interpolates depth in float from the vertices' float
// coordinates, so a fragment may lie a few float ulps (about 1e-7 each) times the triangle's
// conditioning nearer than the exact max_depth; 1e-2 leaves a factor 1e5 for that (slivers of
// aspect up to ~1e5), and a piece just 1% behind a facade is rare (what hides a piece in a city
// is a building in between, tens of percent nearer).
inline constexpr double kOcclusionMargin = 1e-2;

// Whether a polygon with this footprint is hidden on the face: every pixel it may fill already
// holds a depth nearer than any of its points by the margin.
inline bool hidden_behind(const FaceDepthTiles& tiles, const FaceFootprint& fp) {
    if (fp.x0 > fp.x1 || fp.y0 > fp.y1) return true;  // it fills no pixel of this face
    return tiles.covers(fp.x0, fp.y0, fp.x1, fp.y1, fp.max_depth / (1.0 - kOcclusionMargin));
}

}  // namespace ffcube
