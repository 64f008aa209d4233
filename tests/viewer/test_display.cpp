// The viewer's CPU side: the display mesh, flat and smooth colours, the row heat map and the
// hemicube image colours.
#include <gtest/gtest.h>

#include <glm/geometric.hpp>

#include <algorithm>
#include <array>
#include <cmath>
#include <set>

#include "ffcube/scene/load_model.hpp"
#include "ffcube/scene/mesher.hpp"
#include "ffcube/scene/refine.hpp"
#include "ffcube/viewer/display.hpp"
#include "support/scenes.hpp"

namespace ffcube {
namespace {

using test::make_scene;
using test::NamedPolygon;
using test::square_z;

// The unit square facing up, 2 × 2 patches of equal area.
Scene two_by_two() { return make_scene({square_z("floor", 0.0, true)}, 0.5); }

Vec3 vertex_color(const std::vector<float>& c, std::size_t v) { return Vec3(c[3 * v], c[3 * v + 1], c[3 * v + 2]); }

TEST(DisplayMesh, OneVertexPerCornerTwoTrianglesPerQuad) {
    const Scene s = two_by_two();
    ASSERT_EQ(s.size(), 4u);
    const DisplayMesh m = build_display_mesh(s);
    EXPECT_EQ(m.vertex_count(), 16u);
    EXPECT_EQ(m.triangles.size(), 4u * 2 * 3);
    EXPECT_EQ(m.lines.size(), 4u * 4 * 2);
    for (std::uint32_t p = 0; p < 4; ++p) {
        EXPECT_EQ(m.first_vertex[p + 1] - m.first_vertex[p], 4u);
        EXPECT_EQ(m.first_line[p + 1] - m.first_line[p], 8u);
        for (std::uint32_t v = m.first_vertex[p]; v < m.first_vertex[p + 1]; ++v) EXPECT_EQ(m.patch[v], p);
    }
    // Triangles face the patch's normal (CCW from the front): the viewer culls back faces.
    for (std::size_t t = 0; t < m.triangles.size(); t += 3) {
        auto pos = [&](std::uint32_t v) { return Vec3(m.positions[3 * v], m.positions[3 * v + 1], m.positions[3 * v + 2]); };
        const Vec3 a = pos(m.triangles[t]), b = pos(m.triangles[t + 1]), c = pos(m.triangles[t + 2]);
        EXPECT_GT(glm::dot(glm::cross(b - a, c - a), s.patches[m.patch[m.triangles[t]]].normal), 0.0);
    }
}

// Adaptive refinement's wireframe: patch 0 of the 2 × 2 floor split into 2 × 2 elements. Its
// inner cross is 4 segments, each an edge of two children: 8 element edges, every one on the
// patch's midlines (x = 0.25 or y = 0.25, inside [0, 0.5]²). Everything else (the 7 elements'
// 28 edges less those 8) is a patch edge, including the children's halves of patch 0's outline
// and the unsplit patches' shared edges (different starting patches).
TEST(DisplayMesh, ElementEdgesInsideASplitPatchArePatchEdgesElsewhere) {
    const Scene s = two_by_two();
    const std::uint32_t split[4] = {2, 1, 1, 1};
    const RefinedScene r = refine_patches(s, split);
    ASSERT_EQ(r.scene.size(), 7u);
    const DisplayMesh m = build_display_mesh(r.scene, r.parent);
    EXPECT_EQ(m.element_lines.size(), 8u * 2);
    EXPECT_EQ(m.patch_lines.size(), (28u - 8u) * 2);
    EXPECT_EQ(m.lines.size(), 28u * 2);
    // Patch 0: the split one, whichever quarter of the floor it is.
    double lo[2] = {1e300, 1e300}, hi[2] = {-1e300, -1e300};
    for (std::uint32_t k = 0; k < s.patches[0].count; ++k)
        for (int a = 0; a < 2; ++a) {
            lo[a] = std::min(lo[a], s.positions[s.patches[0].v[k]][a]);
            hi[a] = std::max(hi[a], s.positions[s.patches[0].v[k]][a]);
        }
    const auto pos = [&](std::uint32_t v, int a) { return static_cast<double>(m.positions[3 * v + a]); };
    std::set<std::pair<std::array<long, 2>, std::array<long, 2>>> distinct;
    for (std::size_t l = 0; l < m.element_lines.size(); l += 2) {
        const std::uint32_t a = m.element_lines[l], b = m.element_lines[l + 1];
        EXPECT_EQ(r.parent[m.patch[a]], 0u);
        for (int ax = 0; ax < 2; ++ax) {
            // Inside patch 0, not on its outline (1e-9: the corners are sums of exact binary fractions).
            const double mid = 0.5 * (pos(a, ax) + pos(b, ax));
            EXPECT_GT(mid, lo[ax] - 1e-9);
            EXPECT_LT(mid, hi[ax] + 1e-9);
        }
        const bool on_x_mid = std::abs(pos(a, 0) - 0.5 * (lo[0] + hi[0])) < 1e-9 && std::abs(pos(b, 0) - 0.5 * (lo[0] + hi[0])) < 1e-9;
        const bool on_y_mid = std::abs(pos(a, 1) - 0.5 * (lo[1] + hi[1])) < 1e-9 && std::abs(pos(b, 1) - 0.5 * (lo[1] + hi[1])) < 1e-9;
        EXPECT_TRUE(on_x_mid || on_y_mid) << "element edge " << l / 2 << " is not on a midline of patch 0";
        std::array<long, 2> ka{std::lround(pos(a, 0) * 1e6), std::lround(pos(a, 1) * 1e6)};
        std::array<long, 2> kb{std::lround(pos(b, 0) * 1e6), std::lround(pos(b, 1) * 1e6)};
        distinct.insert({std::min(ka, kb), std::max(ka, kb)});
    }
    EXPECT_EQ(distinct.size(), 4u);

    // Without an origin (no refinement) every edge is a patch edge.
    const DisplayMesh plain = build_display_mesh(r.scene);
    EXPECT_TRUE(plain.element_lines.empty());
    EXPECT_EQ(plain.patch_lines, plain.lines);
}

TEST(DisplayMesh, FlatGivesEveryCornerItsPatchValue) {
    const Scene s = two_by_two();
    const DisplayMesh m = build_display_mesh(s);
    const std::vector<Vec3> b = {Vec3(1.0), Vec3(2.0), Vec3(3.0), Vec3(4.0)};
    std::vector<float> c;
    flat_colors(m, b, c);
    for (std::size_t v = 0; v < m.vertex_count(); ++v) EXPECT_EQ(vertex_color(c, v), b[m.patch[v]]);
}

TEST(DisplayMesh, SmoothAveragesThePatchesMeetingAtAPoint) {
    const Scene s = two_by_two();
    const DisplayMesh m = build_display_mesh(s);
    const std::vector<Vec3> b = {Vec3(1.0), Vec3(2.0), Vec3(3.0), Vec3(4.0)};
    std::vector<float> c;
    smooth_colors(m, s, b, c);
    for (std::size_t v = 0; v < m.vertex_count(); ++v) {
        const Vec3 p(m.positions[3 * v], m.positions[3 * v + 1], m.positions[3 * v + 2]);
        // Equal areas: the centre takes the mean of all four, an edge midpoint of its two patches,
        // a corner of the square its own patch's value.
        Vec3 expected(0.0);
        int count = 0;
        for (std::uint32_t q = 0; q < 4; ++q)
            for (std::uint32_t k = 0; k < 4; ++k)
                if (glm::length(s.positions[s.patches[q].v[k]] - p) < 1e-12) expected += b[q], ++count;
        expected /= count;
        EXPECT_NEAR(vertex_color(c, v).r, expected.r, 1e-6) << "vertex at " << p.x << "," << p.y;
    }
    // The centre really is shared by all four (so the check above covers averaging).
    int centre_hits = 0;
    for (std::size_t v = 0; v < m.vertex_count(); ++v)
        if (std::abs(m.positions[3 * v] - 0.5f) < 1e-6f && std::abs(m.positions[3 * v + 1] - 0.5f) < 1e-6f) {
            ++centre_hits;
            EXPECT_NEAR(vertex_color(c, v).r, 2.5, 1e-6);
        }
    EXPECT_EQ(centre_hits, 4);
}

TEST(DisplayMesh, SmoothDoesNotCrossACrease) {
    // Floor z = 0 and a wall x = 0 facing +x, one object, sharing the edge x = 0, z = 0.
    const NamedPolygon floor{"box", {Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(1, 1, 0), Vec3(0, 1, 0)}};
    const NamedPolygon wall{"box", {Vec3(0, 0, 0), Vec3(0, 1, 0), Vec3(0, 1, 1), Vec3(0, 0, 1)}};
    const Scene s = make_scene({floor, wall}, 2.0);
    ASSERT_EQ(s.size(), 2u);
    const DisplayMesh m = build_display_mesh(s);
    const std::vector<Vec3> b = {Vec3(1.0), Vec3(3.0)};
    std::vector<float> c;
    smooth_colors(m, s, b, c);
    for (std::size_t v = 0; v < m.vertex_count(); ++v) EXPECT_EQ(vertex_color(c, v), b[m.patch[v]]);
}

TEST(RowHeatMap, ColoursByDensityOnALogRamp) {
    const Scene s = two_by_two();
    SparseRow row;
    row.col = {1, 2};
    row.val = {0.1, 0.0001};  // equal areas: densities 1 and 1/1000 of the largest
    const std::vector<Vec3> h = row_heat_map(s, 0, row);
    EXPECT_EQ(h[0], kPicked);
    EXPECT_EQ(h[1], heat_color(1.0));
    for (int c = 0; c < 3; ++c) EXPECT_NEAR(h[2][c], heat_color(0.0)[c], 1e-12);
    EXPECT_EQ(h[3], kNoContribution);
}

TEST(RowHeatMap, RampBrightensMonotonicallyAndAvoidsTheMarkers) {
    auto luminance = [](const Vec3& c) { return 0.2126 * c.r + 0.7152 * c.g + 0.0722 * c.b; };
    double previous = -1.0;
    for (int k = 0; k <= 100; ++k) {
        const Vec3 c = heat_color(k / 100.0);
        EXPECT_GT(luminance(c), previous);
        previous = luminance(c);
        // The markers stay distinguishable from every ramp colour (by more than 8-bit rounding).
        EXPECT_GT(glm::length(c - kPicked), 0.1);
        EXPECT_GT(glm::length(c - kNoContribution), 0.1);
    }
}

// examples/lidded_box.vs3: the open unit box (5 S surfaces) and an obstruction-only lid (O) at
// z = 1, each surface one patch.
Scene lidded_box() {
    MeshOptions o;
    o.subdivide = false;
    return build_scene(load_model(std::string(FFCUBE_SOURCE_DIR) + "/examples/lidded_box.vs3"), o);
}

TEST(ObstructionMesh, TheLidIsDrawnApartAndHasNoPatchColour) {
    const Scene s = lidded_box();
    ASSERT_EQ(s.size(), 5u);
    ASSERT_TRUE(s.drawn);
    const ObstructionMesh o = build_obstruction_mesh(s);
    EXPECT_EQ(o.patches, 1u);
    ASSERT_EQ(o.positions.size(), 4u * 3);  // the lid's 4 corners
    EXPECT_EQ(o.triangles.size(), 2u * 3);
    EXPECT_EQ(o.lines.size(), 4u * 2);
    for (std::size_t v = 0; v < 4; ++v) {
        EXPECT_EQ(o.positions[3 * v + 2], 1.0f);  // z = 1
        for (int c = 0; c < 2; ++c) EXPECT_TRUE(o.positions[3 * v + c] == 0.0f || o.positions[3 * v + c] == 1.0f);
    }
    // The radiating mesh holds the five S surfaces only: colours (radiosity, heat maps) are per
    // radiating patch, and no vertex of it lies inside the lid (z = 1 only on the walls' top edges).
    const DisplayMesh m = build_display_mesh(s);
    EXPECT_EQ(m.first_vertex.size(), s.size() + 1);
    for (std::uint32_t p : m.patch) EXPECT_LT(p, s.size());
    std::vector<float> colours;
    flat_colors(m, std::vector<Vec3>(s.size(), Vec3(1.0)), colours);
    EXPECT_EQ(colours.size(), 3 * m.vertex_count());
    // Meshed, the lid is a grid on each of its two back-to-back faces, each face's grid points
    // made from its own corner order: drawn once all the same (one layer of glass), every cell.
    MeshOptions fine;
    fine.max_patch_edge = 0.15;  // 7 x 7 cells
    const Scene meshed = build_scene(load_model(std::string(FFCUBE_SOURCE_DIR) + "/examples/lidded_box.vs3"), fine);
    ASSERT_TRUE(meshed.drawn);
    EXPECT_EQ(meshed.drawn->size() - meshed.drawn->obstruction_first, 2u * 49);
    const ObstructionMesh grid = build_obstruction_mesh(meshed);
    EXPECT_EQ(grid.patches, 49u);
    double area = 0.0;
    for (std::size_t t = 0; t < grid.triangles.size(); t += 3) {
        auto pos = [&](std::uint32_t v) { return Vec3(grid.positions[3 * v], grid.positions[3 * v + 1], grid.positions[3 * v + 2]); };
        area += 0.5 * glm::length(glm::cross(pos(grid.triangles[t + 1]) - pos(grid.triangles[t]), pos(grid.triangles[t + 2]) - pos(grid.triangles[t])));
    }
    EXPECT_NEAR(area, 1.0, 1e-6);  // the unit lid once (float corners)
    // A scene without O surfaces draws none.
    EXPECT_EQ(build_obstruction_mesh(two_by_two()).patches, 0u);
    EXPECT_TRUE(build_obstruction_mesh(two_by_two()).triangles.empty());
    // The glass colour stays apart from the row heat map's markers.
    EXPECT_GT(glm::length(kObstruction - kNoContribution), 0.1);
    EXPECT_GT(glm::length(kObstruction - kPicked), 0.1);
}

TEST(ItemColor, BackgroundBackFacesAndDistinctPatches) {
    EXPECT_EQ(item_color(0), 0xFF000000u);
    EXPECT_EQ(item_color(0xFFFFFFFFu), 0xFF404040u);
    for (std::uint32_t id = 1; id < 2000; ++id) {
        const std::uint32_t c = item_color(id);
        for (int ch = 0; ch < 3; ++ch) EXPECT_GE((c >> (8 * ch)) & 0xFFu, 96u);  // brighter than the markers
        EXPECT_NE(c, item_color(id + 1));
    }
}

}  // namespace
}  // namespace ffcube
