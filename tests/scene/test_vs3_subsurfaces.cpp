// View3D subsurfaces and null surfaces (src/scene/vs3_subsurfaces.hpp, vs3_loader.cpp): the base
// keeps what they leave of it, as convex pieces that tile it exactly.
#include <gtest/gtest.h>

#include <glm/geometric.hpp>
#include <string>
#include <vector>

#include "ffcube/scene/mesher.hpp"
#include "ffcube/scene/vs3_loader.hpp"
#include "scene/vs3_subsurfaces.hpp"
#include "support/view3d_text.hpp"

namespace ffcube {
namespace {

double total_area(const std::vector<std::vector<Vec3>>& pieces) {
    double a = 0.0;
    for (const auto& p : pieces) a += polygon_area(p);
    return a;
}

// Every piece is a triangle or a convex quad, counter-clockwise like the base (its normal), and
// in the base's plane; together they have the base's area less the holes'; no piece's centroid
// lies in a hole.
void expect_tiling(const std::vector<Vec3>& base, const std::vector<std::vector<Vec3>>& holes,
                   const std::vector<std::vector<Vec3>>& pieces) {
    double expected = polygon_area(base);
    for (const auto& h : holes) expected -= polygon_area(h);
    // Sums of a few products of coordinates of size 1: rounding, 1e-14 with room.
    EXPECT_NEAR(total_area(pieces), expected, 1e-14);
    const Vec3 n = polygon_normal(base);
    for (const auto& p : pieces) {
        ASSERT_TRUE(p.size() == 3 || p.size() == 4) << p.size();
        EXPECT_NEAR(glm::dot(polygon_normal(p), n), 1.0, 1e-12);
        for (const Vec3& v : p) EXPECT_NEAR(glm::dot(v - base[0], n), 0.0, 1e-14);
        for (std::size_t k = 0; k < p.size(); ++k) {  // convex: every turn is to the left
            const Vec3 e0 = p[(k + 1) % p.size()] - p[k], e1 = p[(k + 2) % p.size()] - p[(k + 1) % p.size()];
            EXPECT_GT(glm::dot(glm::cross(e0, e1), n), 0.0);
        }
        const Vec3 c = polygon_centroid(p);
        for (const auto& h : holes) {
            bool inside = true;
            const Vec3 hn = polygon_normal(h);
            for (std::size_t k = 0; k < h.size(); ++k)
                inside = inside && glm::dot(glm::cross(h[(k + 1) % h.size()] - h[k], c - h[k]), hn) > 0.0;
            EXPECT_FALSE(inside);
        }
    }
}

TEST(Vs3Subsurfaces, CutHolesTilesTheRest) {
    const std::vector<Vec3> wall = {{0, 0, 0}, {2, 0, 0}, {2, 2, 0}, {0, 2, 0}};
    // A window in the middle; a door touching the bottom edge beside another window; a
    // triangular hole the other way round (a null surface faces its base).
    const std::vector<std::vector<std::vector<Vec3>>> cases = {
        {{{0.5, 0.5, 0}, {1.5, 0.5, 0}, {1.5, 1.5, 0}, {0.5, 1.5, 0}}},
        {{{0.2, 0, 0}, {0.8, 0, 0}, {0.8, 1.5, 0}, {0.2, 1.5, 0}}, {{1.1, 0.9, 0}, {1.8, 0.9, 0}, {1.8, 1.6, 0}, {1.1, 1.6, 0}}},
        {{{1.5, 0.5, 0}, {0.5, 0.5, 0}, {1.0, 1.7, 0}}},
    };
    for (const auto& holes : cases) expect_tiling(wall, holes, detail::cut_holes(wall, holes));
    // A triangular base with a hole sharing one of its corners.
    const std::vector<Vec3> tri = {{0, 0, 1}, {0, 3, 1}, {0, 0, 4}};  // x = 1 plane... facing +x
    const std::vector<std::vector<Vec3>> corner = {{{0, 0, 1}, {0, 1, 1}, {0, 0, 2}}};
    expect_tiling(tri, corner, detail::cut_holes(tri, corner));
    // Without holes: the base as it is.
    EXPECT_EQ(detail::cut_holes(wall, {}), (std::vector<std::vector<Vec3>>{wall}));
}

const std::string kWallWithWindow = std::string("T wall, window, null surface\n") + test::kVs3WindowWallVertices + R"(V 9 0.2 1.6 0
V 10 0.4 1.6 0
V 11 0.4 1.8 0
S 1 1 2 3 4 0 0 0.9 wall
S 2 5 6 7 8 1 0 0.8 window
N 3 11 10 9 0 1 0 0.9 vent
)";

TEST(Vs3Subsurfaces, TheBaseKeepsWhatTheyLeave) {
    const ObjModel m = parse_vs3(kWallWithWindow, "w.vs3");
    // Objects: wall, window, then the null surface as an obstruction-only object.
    EXPECT_EQ(m.objects, (std::vector<std::string>{"wall", "window", "vent"}));
    EXPECT_EQ(m.obstruction_objects, 1u);
    double wall = 0.0, window = 0.0, vent = 0.0;
    for (const ObjFace& f : m.faces) {
        std::vector<Vec3> p;
        for (const auto v : f.v) p.push_back(m.positions[v]);
        (f.object == 0 ? wall : f.object == 1 ? window : vent) += polygon_area(p);
        EXPECT_EQ(f.line, f.object == 0 ? 14u : f.object == 1 ? 15u : 16u);
    }
    EXPECT_NEAR(window, 1.0, 1e-15);
    EXPECT_NEAR(vent, 2 * 0.02, 1e-15);  // two faces back to back
    EXPECT_NEAR(wall, 4.0 - 1.0 - 0.02, 1e-14);
    // Each piece is one patch as given.
    MeshOptions o;
    o.subdivide = false;
    const Scene s = build_scene(m, o);
    double patches = 0.0;
    for (const Patch& p : s.patches) patches += p.object == 0 ? p.area : 0.0;
    EXPECT_NEAR(patches, 2.98, 1e-14);
}

}  // namespace
}  // namespace ffcube
