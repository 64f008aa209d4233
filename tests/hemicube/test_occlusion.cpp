// The CPU half of occlusion culling (hemicube/occlusion.hpp), against brute force: a polygon's
// footprint holds every pixel whose centre's ray meets the polygon at or beyond the near plane
// (what the rasterizer fills, without its snapping) and bounds the depth there, also for
// polygons that cross a face's eye plane; the row minima answer exactly what a scan of the
// rectangle's pixels answers.
#include <gtest/gtest.h>

#include <glm/geometric.hpp>

#include <cmath>
#include <random>

#include "ffcube/hemicube/occlusion.hpp"

namespace ffcube {
namespace {

// The point where the ray from the eye (the origin) along dir meets triangle t, if it does
// (Möller–Trumbore, no tolerance: the test below only uses hits well inside by a margin).
std::optional<Vec3> ray_hit(const Vec3& dir, const std::vector<Vec3>& t) {
    const Vec3 e1 = t[1] - t[0], e2 = t[2] - t[0];
    const Vec3 p = glm::cross(dir, e2);
    const double det = glm::dot(e1, p);
    if (std::abs(det) < 1e-300) return std::nullopt;
    const Vec3 s = -t[0];
    const double u = glm::dot(s, p) / det;
    const Vec3 q = glm::cross(s, e1);
    const double v = glm::dot(dir, q) / det;
    const double tt = glm::dot(e2, q) / det;
    // Inside by 1e-9 in barycentrics: a centre on an edge may or may not be filled either way,
    // and the footprint's one-pixel growth covers the edge (rounding of this test aside).
    if (u < 1e-9 || v < 1e-9 || u + v > 1 - 1e-9 || tt <= 0) return std::nullopt;
    return tt * dir;
}

// Random triangles all around the eye (many crossing the side faces' eye planes and the
// hemicube plane), every pixel centre of every face tested: the rasterization of the exact
// triangle, clipped by the near plane, lies within the footprint and within its depth bound.
TEST(OcclusionFootprint, HoldsEveryPixelTheClippedPolygonFillsAndBoundsItsDepth) {
    const HemicubeLayout lay(32);
    const double near = 0.05;
    std::mt19937_64 rng(7);
    std::uniform_real_distribution<double> u(-1, 1), w(0, 1);
    std::size_t filled = 0, crossing_bounded = 0, crossing_culled_rect = 0, empty = 0, with_edges = 0;
    for (int t = 0; t < 400; ++t) {
        const double scale = 0.2 * std::pow(50.0, w(rng));
        std::vector<Vec3> tri;
        for (int k = 0; k < 3; ++k) tri.emplace_back(scale * u(rng), scale * u(rng), scale * (1.2 * w(rng) - 0.2));
        for (const FaceSpec& f : lay.faces()) {
            const FaceFootprint fp = face_footprint(f, tri, near);
            bool crosses = false;
            for (const Vec3& v : tri) crosses = crosses || glm::dot(v, f.forward) <= 0;
            const bool none = fp.x0 > fp.x1 || fp.y0 > fp.y1;
            empty += none;
            with_edges += fp.edges > 0;
            if (crosses && !none) {
                ++crossing_bounded;
                // Smaller than the whole face: something a tile scan could now cull.
                if (fp.max_depth < 1 && (fp.x1 - fp.x0 + 1) * (fp.y1 - fp.y0 + 1) < f.viewport.width * f.viewport.height)
                    ++crossing_culled_rect;
            }
            const FaceFrustum& fr = f.frustum;
            const double sx = (fr.right - fr.left) / f.viewport.width, sy = (fr.top - fr.bottom) / f.viewport.height;
            for (int y = 0; y < f.viewport.height; ++y)
                for (int x = 0; x < f.viewport.width; ++x) {
                    const Vec3 dir = HemicubeLayout::face_direction(f, fr.left + (x + 0.5) * sx, fr.bottom + (y + 0.5) * sy);
                    const std::optional<Vec3> p = ray_hit(dir, tri);
                    if (!p) continue;
                    const double d = glm::dot(*p, f.forward);
                    if (d < near) continue;  // clipped by GL: no fragment
                    ++filled;
                    ASSERT_FALSE(none) << "triangle " << t << " face " << int(f.face) << " fills (" << x << ", " << y << ")";
                    EXPECT_TRUE(x >= fp.x0 && x <= fp.x1 && y >= fp.y0 && y <= fp.y1)
                        << "pixel (" << x << ", " << y << ") outside [" << fp.x0 << ", " << fp.x1 << "] × [" << fp.y0
                        << ", " << fp.y1 << "]";
                    // Every half-plane holds the pixel's centre (they carry a one-pixel
                    // margin; here the test needs none).
                    for (int e = 0; e < fp.edges; ++e) {
                        const auto& [nx, ny, c] = fp.edge[static_cast<std::size_t>(e)];
                        EXPECT_LE(nx * (x + 0.5) + ny * (y + 0.5), c - 1.0 + 1e-9) << "edge " << e << " of triangle " << t;
                    }
                    // The probe pixel, if any, is one of the footprint's: inside the
                    // rectangle and every half-plane.
                    if (fp.probe_x >= 0) {
                        EXPECT_TRUE(fp.probe_x >= fp.x0 && fp.probe_x <= fp.x1 && fp.probe_y >= fp.y0 && fp.probe_y <= fp.y1);
                        for (int e = 0; e < fp.edges; ++e) {
                            const auto& [nx, ny, c] = fp.edge[static_cast<std::size_t>(e)];
                            EXPECT_LE(nx * (fp.probe_x + 0.5) + ny * (fp.probe_y + 0.5), c);
                        }
                    }
                    // The bound is near / (least distance of the clipped polygon): 1e-12
                    // relative is the rounding of the two computations of d.
                    EXPECT_LE(near / d, fp.max_depth * (1 + 1e-12));
                }
        }
    }
    EXPECT_GT(filled, 100000u);
    // Triangles crossing a face's eye plane now get a bounded footprint (before: never culled),
    // often smaller than the face with depth below 1; and some miss a face's frustum altogether
    // (across a corner, which the per-plane outcodes do not catch).
    EXPECT_GT(crossing_bounded, 400u);  // 831 with seed 7
    EXPECT_GT(crossing_culled_rect, 300u);  // 724 of 831 with seed 7
    EXPECT_GT(empty, 0u);
    EXPECT_GT(with_edges, 500u);
}

// A polygon wholly nearer than the near plane fills nothing; one reaching it gets depth 1 (the
// largest there is: never culled).
TEST(OcclusionFootprint, NearPlane) {
    const HemicubeLayout lay(16);
    const FaceSpec& top = lay.face(HemicubeFace::Top);
    const double near = 0.1;
    const std::vector<Vec3> small{{-0.01, -0.01, 0.05}, {0.01, -0.01, 0.05}, {0.0, 0.01, 0.05}};
    const FaceFootprint a = face_footprint(top, small, near);
    EXPECT_TRUE(a.x0 > a.x1 || a.y0 > a.y1);
    const std::vector<Vec3> through{{-0.01, -0.01, 0.05}, {0.01, -0.01, 0.05}, {0.0, 0.01, 1.0}};
    const FaceFootprint b = face_footprint(top, through, near);
    EXPECT_LE(b.x0, b.x1);
    EXPECT_DOUBLE_EQ(b.max_depth, 1.0);
}

// Random depth images with holes (0: nothing drawn) and runs of equal values; rectangles of every
// size on viewports of odd and even sizes; thresholds at, just below and just above pixel
// values: the row minima's answer equals the scan's every time.
TEST(OcclusionRows, EqualsAScanOfTheRectanglesPixels) {
    std::mt19937_64 rng(3);
    const int aw = 80, ah = 70;
    std::vector<float> depth(static_cast<std::size_t>(aw) * ah);
    std::uniform_real_distribution<float> dv(0.1f, 1.0f);
    std::uniform_real_distribution<double> w(0, 1);
    for (const AtlasViewport vp : {AtlasViewport{0, 0, 64, 64}, AtlasViewport{64, 0, 16, 8}, AtlasViewport{3, 5, 37, 19},
                                   AtlasViewport{10, 20, 1, 1}, AtlasViewport{0, 1, 64, 32}, AtlasViewport{7, 3, 33, 65}}) {
        for (int image = 0; image < 6; ++image) {
            // Large blocks of one value (occluders), a few holes and single-pixel dips.
            const float base = dv(rng);
            for (float& v : depth) v = base;
            for (int b = 0; b < 8; ++b) {
                std::uniform_int_distribution<int> xs(0, aw - 1), ys(0, ah - 1);
                const int x0 = xs(rng), y0 = ys(rng), x1 = std::min(aw - 1, x0 + xs(rng) / 3), y1 = std::min(ah - 1, y0 + ys(rng) / 3);
                const float v = image % 2 ? dv(rng) : base * 1.5f;
                for (int y = y0; y <= y1; ++y)
                    for (int x = x0; x <= x1; ++x) depth[static_cast<std::size_t>(y) * aw + x] = v;
            }
            for (int h = 0; h < image; ++h) depth[std::uniform_int_distribution<std::size_t>(0, depth.size() - 1)(rng)] = h % 2 ? 0.0f : 0.05f;
            FaceDepthRows rows;
            rows.build(depth, aw, vp);
            ASSERT_EQ(rows.width(), vp.width);
            ASSERT_EQ(rows.height(), vp.height);
            std::uniform_int_distribution<int> xs(0, vp.width - 1), ys(0, vp.height - 1);
            for (int t = 0; t < 400; ++t) {
                int x0 = xs(rng), x1 = xs(rng), y0 = ys(rng), y1 = ys(rng);
                if (x0 > x1) std::swap(x0, x1);
                if (y0 > y1) std::swap(y0, y1);
                if (t % 3 == 0) x1 = std::min(vp.width - 1, x0 + t % 5), y1 = std::min(vp.height - 1, y0 + t % 4);  // small
                float exact = INFINITY;
                for (int y = y0; y <= y1; ++y)
                    for (int x = x0; x <= x1; ++x)
                        exact = std::min(exact, depth[static_cast<std::size_t>(vp.y + y) * aw + vp.x + x]);
                // Thresholds around the exact minimum and around a random pixel's value.
                const float any = depth[static_cast<std::size_t>(vp.y + ys(rng)) * aw + vp.x + xs(rng)];
                for (const double d : {double(exact), std::nextafter(double(exact), 0.0), std::nextafter(double(exact), 2.0),
                                       double(any), 0.5 * exact, w(rng)}) {
                    ASSERT_EQ(rows.covers(x0, y0, x1, y1, d), double(exact) > d)
                        << "rect [" << x0 << ", " << x1 << "] × [" << y0 << ", " << y1 << "] d " << d << " min " << exact;
                }
            }
            // With half-planes (random lines through the rectangle, either side): the scan
            // keeps the pixels whose centres satisfy them all.
            std::uniform_real_distribution<double> ang(0, 6.283185307179586);
            for (int t = 0; t < 300; ++t) {
                FaceFootprint fp{};
                fp.x0 = xs(rng), fp.x1 = xs(rng), fp.y0 = ys(rng), fp.y1 = ys(rng);
                if (fp.x0 > fp.x1) std::swap(fp.x0, fp.x1);
                if (fp.y0 > fp.y1) std::swap(fp.y0, fp.y1);
                fp.edges = 1 + t % 4;
                for (int e = 0; e < fp.edges; ++e) {
                    const double a = ang(rng);
                    const double cx = fp.x0 + w(rng) * (fp.x1 - fp.x0 + 1), cy = fp.y0 + w(rng) * (fp.y1 - fp.y0 + 1);
                    fp.edge[static_cast<std::size_t>(e)] = {std::cos(a), std::sin(a), std::cos(a) * cx + std::sin(a) * cy + 0.5};
                }
                float exact = INFINITY;
                for (int y = fp.y0; y <= fp.y1; ++y)
                    for (int x = fp.x0; x <= fp.x1; ++x) {
                        bool in = true;
                        for (int e = 0; e < fp.edges; ++e) {
                            const auto& [nx, ny, c] = fp.edge[static_cast<std::size_t>(e)];
                            in = in && nx * (x + 0.5) + ny * (y + 0.5) <= c;
                        }
                        if (in) exact = std::min(exact, depth[static_cast<std::size_t>(vp.y + y) * aw + vp.x + x]);
                    }
                for (const double d : {double(exact), std::nextafter(double(exact), 0.0), 0.5 * exact, w(rng)}) {
                    if (std::isinf(exact) && d == exact) continue;
                    ASSERT_EQ(rows.covers(fp, d), double(exact) > d) << "footprint " << t << " d " << d << " min " << exact;
                }
            }
            EXPECT_TRUE(rows.covers(1, 1, 0, 0, 1.0));  // an empty rectangle
        }
    }
}

TEST(OcclusionRows, HiddenBehindNeedsTheMargin) {
    const HemicubeLayout lay(16);
    const FaceSpec& top = lay.face(HemicubeFace::Top);
    std::vector<float> depth(static_cast<std::size_t>(lay.atlas_width()) * lay.atlas_height(), 0.5f);
    FaceDepthRows rows;
    rows.build(depth, lay.atlas_width(), top.viewport);
    FaceFootprint fp{};
    fp.x0 = fp.y0 = 2;
    fp.x1 = fp.y1 = 5;
    fp.max_depth = 0.5 * (1 - kOcclusionMargin) * 0.999;
    EXPECT_TRUE(hidden_behind(rows, fp));
    fp.max_depth = 0.5 * (1 - kOcclusionMargin) * 1.001;  // within the margin of the occluders
    EXPECT_FALSE(hidden_behind(rows, fp));
    fp.x0 = 3, fp.x1 = 2;  // misses the face: no pixel to fill
    EXPECT_TRUE(hidden_behind(rows, fp));
}


// Occlusion culling by hierarchy nodes (hide_hidden_nodes) against the piece test it spares:
// every (piece, face) a hidden node marks is one that hidden_behind finds hidden from the piece's
// own footprint, made from its corners rounded to float in the hemicube's frame as the worker
// makes them. Clusters of triangles all around the eye (near it, crossing its planes, far behind
// walls, just behind a wall's depth by less than and more than the margin), behind depth images
// of walls at several distances with holes; at the origin and at 1e5 (where a float corner is
// 2^-24 of 1e5 off); a walk that marks nothing would pass, so the marks must also be many.
TEST(OcclusionNodes, EveryMarkIsAPieceTheFootprintTestHides) {
    std::mt19937_64 rng(11);
    std::uniform_real_distribution<double> u(-1, 1), w(0, 1);
    std::size_t marks = 0, hidden_pieces = 0, nodes = 0;
    for (const double offset : {0.0, 1e5}) {
        for (int scene = 0; scene < 12; ++scene) {
            const HemicubeLayout lay(scene % 2 ? 64 : 32);
            const double near = 0.01;
            const Vec3 eye = Vec3(offset, -0.5 * offset, 0.25 * offset) + Vec3(u(rng), u(rng), u(rng));
            const Vec3 normal = glm::normalize(Vec3(u(rng), u(rng), u(rng)) + (scene % 3 == 0 ? Vec3(0, 0, 4) : Vec3(0.0)));
            const HemicubeFrame frame = make_frame(normal, 6.283185307179586 * w(rng));
            // Triangles in clusters (so that nodes group neighbours), in the local frame first.
            std::vector<std::array<Vec3, 3>> tris;
            for (int c = 0; c < 40; ++c) {
                const Vec3 dir = glm::normalize(Vec3(u(rng), u(rng), u(rng)));
                const double dist = c < 4 ? 0.02 + 0.1 * w(rng) : 0.5 + 20 * w(rng) * w(rng);
                const Vec3 centre = dist * dir;
                const double size = (c % 5 == 0 ? 0.5 : 0.05) * dist;
                for (int t = 0; t < 30; ++t) {
                    const Vec3 at = centre + size * Vec3(u(rng), u(rng), u(rng));
                    const double s = 0.2 * size * (0.05 + w(rng));
                    tris.push_back({at, at + s * Vec3(u(rng), u(rng), u(rng)), at + s * Vec3(u(rng), u(rng), u(rng))});
                }
            }
            // World corners, then their local floats as the worker makes them (gl/hemicube_worker.cpp).
            std::vector<BvhBox> boxes;
            std::vector<std::array<Vec3, 3>> local;
            for (const auto& t : tris) {
                std::array<Vec3, 3> world, loc;
                for (int k = 0; k < 3; ++k) world[k] = eye + frame.to_world(t[k]);
                BvhBox b{world[0], world[0]};
                for (int k = 0; k < 3; ++k) {
                    b.lo = glm::min(b.lo, world[k]);
                    b.hi = glm::max(b.hi, world[k]);
                    const Vec3 d = world[k] - eye;
                    loc[k] = Vec3(static_cast<float>(glm::dot(d, frame.tangent)), static_cast<float>(glm::dot(d, frame.bitangent)),
                                  static_cast<float>(glm::dot(d, frame.normal)));
                }
                boxes.push_back(b);
                local.push_back(loc);
            }
            const PieceBvh bvh(boxes);
            // Depth images: per face walls (rectangles of one depth near / D) over a background
            // wall, with holes (0: nothing drawn).
            std::vector<float> depth(static_cast<std::size_t>(lay.atlas_width()) * lay.atlas_height(), 0.0f);
            for (const FaceSpec& f : lay.faces()) {
                const AtlasViewport& vp = f.viewport;
                const float back = static_cast<float>(near / (0.3 + 3 * w(rng)));
                for (int y = 0; y < vp.height; ++y)
                    for (int x = 0; x < vp.width; ++x) depth[static_cast<std::size_t>(vp.y + y) * lay.atlas_width() + vp.x + x] = back;
                for (int b = 0; b < 6; ++b) {
                    std::uniform_int_distribution<int> xs(0, vp.width - 1), ys(0, vp.height - 1);
                    const int x0 = xs(rng), y0 = ys(rng), x1 = std::min(vp.width - 1, x0 + xs(rng) / 2),
                              y1 = std::min(vp.height - 1, y0 + ys(rng) / 2);
                    const float v = b == 5 ? 0.0f : static_cast<float>(near / (0.2 + 5 * w(rng)));
                    for (int y = y0; y <= y1; ++y)
                        for (int x = x0; x <= x1; ++x) depth[static_cast<std::size_t>(vp.y + y) * lay.atlas_width() + vp.x + x] = v;
                }
            }
            std::array<FaceDepthRows, 5> rows;
            for (std::size_t f = 0; f < 5; ++f) rows[f].build(depth, lay.atlas_width(), lay.faces()[f].viewport);
            HiddenFaces hidden;
            nodes += hide_hidden_nodes(bvh, lay.faces(), rows, eye, frame, near, 0x1f, hidden);
            for (std::uint32_t g = 0; g < tris.size(); ++g) {
                for (std::size_t f = 0; f < 5; ++f) {
                    FaceFootprint fp = face_footprint(lay.faces()[f], local[g], near, false);
                    const bool shows = fp.x0 <= fp.x1 && fp.y0 <= fp.y1;
                    const bool piece = hidden_behind(rows[f], fp);
                    hidden_pieces += shows && piece;
                    if (hidden.of(g) & (1u << f)) {
                        ++marks;
                        ASSERT_TRUE(piece) << "offset " << offset << " scene " << scene << " piece " << g << " face " << f;
                    }
                }
            }
        }
    }
    // Not vacuous: nodes were hidden, and they marked a good share of the pieces on a face that
    // the piece test hides (about half of the clusters lie behind some wall's depth).
    EXPECT_GT(nodes, 100u);
    EXPECT_GT(marks, hidden_pieces / 4) << marks << " of " << hidden_pieces;
}

}  // namespace
}  // namespace ffcube
