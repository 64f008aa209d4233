// The CPU half of occlusion culling (hemicube/occlusion.hpp), against brute force: a polygon's
// footprint holds the pixel of every point of it (pixel_of_direction, the layout's own rule) and
// bounds its depth; the tiles' answer agrees with the minimum over every pixel.
#include <gtest/gtest.h>

#include <glm/geometric.hpp>

#include <cmath>
#include <random>

#include "ffcube/hemicube/occlusion.hpp"

namespace ffcube {
namespace {

TEST(OcclusionTiles, FootprintHoldsEveryPointOfThePolygonAndBoundsItsDepth) {
    const HemicubeLayout lay(64);
    const double near = 1e-3;
    std::mt19937_64 rng(7);
    std::uniform_real_distribution<double> u(-1, 1), w(0, 1);
    std::size_t checked = 0, unbounded = 0;
    for (int t = 0; t < 2000; ++t) {
        // A random triangle in the hemisphere above the eye, 0.2–20 away.
        const double scale = 0.2 * std::pow(100.0, w(rng));
        std::vector<Vec3> tri;
        for (int k = 0; k < 3; ++k) tri.emplace_back(scale * u(rng), scale * u(rng), scale * w(rng) + 0.01);
        for (const FaceSpec& f : lay.faces()) {
            const std::optional<FaceFootprint> fp = face_footprint(f, tri, near);
            if (!fp) {
                ++unbounded;
                continue;
            }
            for (int s = 0; s < 50; ++s) {
                double a = w(rng), b = w(rng);
                if (a + b > 1) a = 1 - a, b = 1 - b;
                const Vec3 p = tri[0] + a * (tri[1] - tri[0]) + b * (tri[2] - tri[0]);
                const auto px = lay.pixel_of_direction(p);
                if (!px || px->face != f.face) continue;
                const int x = px->x - f.viewport.x, y = px->y - f.viewport.y;
                ++checked;
                EXPECT_TRUE(x >= fp->x0 && x <= fp->x1 && y >= fp->y0 && y <= fp->y1)
                    << "pixel (" << x << ", " << y << ") outside [" << fp->x0 << ", " << fp->x1 << "] × [" << fp->y0
                    << ", " << fp->y1 << "]";
                // Depth near / (distance along forward) of the point is at most the bound.
                EXPECT_LE(near / glm::dot(p, f.forward), fp->max_depth * (1 + 1e-12));
            }
        }
    }
    EXPECT_GT(checked, 20000u);
    EXPECT_GT(unbounded, 0u);  // triangles reaching behind a side face's eye plane get none
}

TEST(OcclusionTiles, TilesAgreeWithTheMinimumOverEveryPixel) {
    const HemicubeLayout lay(40);  // 20-pixel side faces: tiles cut by the viewport's edge
    std::vector<float> depth(static_cast<std::size_t>(lay.atlas_width()) * lay.atlas_height());
    std::mt19937_64 rng(3);
    std::uniform_real_distribution<float> d(0.1f, 1.0f);
    for (float& v : depth) v = d(rng);
    depth[5 * lay.atlas_width() + 7] = 0.0f;  // one pixel where nothing was drawn
    for (const FaceSpec& f : lay.faces()) {
        FaceDepthTiles tiles;
        tiles.build(depth, lay.atlas_width(), f.viewport);
        std::uniform_int_distribution<int> xs(0, f.viewport.width - 1), ys(0, f.viewport.height - 1);
        for (int t = 0; t < 500; ++t) {
            int x0 = xs(rng), x1 = xs(rng), y0 = ys(rng), y1 = ys(rng);
            if (x0 > x1) std::swap(x0, x1);
            if (y0 > y1) std::swap(y0, y1);
            float exact = 2;  // min over the rectangle's pixels
            for (int y = y0; y <= y1; ++y)
                for (int x = x0; x <= x1; ++x)
                    exact = std::min(exact, depth[static_cast<std::size_t>(f.viewport.y + y) * lay.atlas_width() + f.viewport.x + x]);
            const double below = 0.5 * exact;
            // Never true when some pixel is not nearer than the test depth.
            EXPECT_FALSE(tiles.covers(x0, y0, x1, y1, exact));
            // True for a small enough depth whenever the rectangle is a union of whole tiles
            // (otherwise the tiles' minimum may come from pixels outside it).
            const int k = FaceDepthTiles::kTile;
            const bool whole = x0 % k == 0 && y0 % k == 0 && ((x1 + 1) % k == 0 || x1 == f.viewport.width - 1) &&
                               ((y1 + 1) % k == 0 || y1 == f.viewport.height - 1);
            if (whole) {
                EXPECT_EQ(tiles.covers(x0, y0, x1, y1, below), exact > 0);
            }
        }
        // Nothing drawn anywhere in a tile: never covered.
        EXPECT_TRUE(tiles.covers(1, 1, 0, 0, 1.0));  // an empty rectangle
    }
}

TEST(OcclusionTiles, HiddenBehindNeedsTheMargin) {
    const HemicubeLayout lay(16);
    const FaceSpec& top = lay.face(HemicubeFace::Top);
    std::vector<float> depth(static_cast<std::size_t>(lay.atlas_width()) * lay.atlas_height(), 0.5f);
    FaceDepthTiles tiles;
    tiles.build(depth, lay.atlas_width(), top.viewport);
    FaceFootprint fp{2, 2, 5, 5, 0.5 * (1 - kOcclusionMargin) * 0.999};
    EXPECT_TRUE(hidden_behind(tiles, fp));
    fp.max_depth = 0.5 * (1 - kOcclusionMargin) * 1.001;  // within the margin of the occluders
    EXPECT_FALSE(hidden_behind(tiles, fp));
    fp = FaceFootprint{3, 0, 2, 5, 1.0};  // misses the face: no pixel to fill
    EXPECT_TRUE(hidden_behind(tiles, fp));
}

}  // namespace
}  // namespace ffcube
