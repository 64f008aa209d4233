// Splitting patches into elements (scene/refine.hpp): the elements tile their patch exactly, keep
// its plane, object and material, and the grids stay in the layout the renderer and the hemicube
// pieces read.
#include <gtest/gtest.h>

#include <glm/geometric.hpp>

#include <numeric>

#include "ffcube/scene/refine.hpp"
#include "support/scenes.hpp"

namespace ffcube {
namespace {

// A 2 × 2 quad floor and a triangle (4 similar triangles at edge 0.75), two objects.
Scene quad_and_triangle() {
    NamedPolygon tri{"tri", {Vec3(0, 0, 1), Vec3(1, 0, 1), Vec3(0, 1, 1)}};
    return test::make_scene({test::square_z("floor", 0.0, true), tri}, 0.75);
}

TEST(RefinePatches, ElementsTileTheirPatchAndKeepItsSurface) {
    const Scene s = quad_and_triangle();
    ASSERT_EQ(s.size(), 4u + 4u);
    std::vector<std::uint32_t> split(s.size(), 1);
    split[1] = 2;  // a floor quad into 4
    split[3] = 3;  // another into 9
    split[5] = 2;  // a triangle (upright or inverted) into 4
    const RefinedScene r = refine_patches(s, split);
    EXPECT_EQ(r.scene.size(), 8u + 3u + 8u + 3u);
    ASSERT_EQ(r.parent.size(), r.scene.size());
    // Every element lies in its parent's plane with its normal, object and material, and the
    // elements' areas add up to the parent's (to rounding: a few ulps of the area per element).
    std::vector<double> area(s.size(), 0.0);
    std::vector<std::size_t> count(s.size(), 0);
    for (std::size_t e = 0; e < r.scene.size(); ++e) {
        const Patch& el = r.scene.patches[e];
        const Patch& p = s.patches[r.parent[e]];
        area[r.parent[e]] += el.area;
        ++count[r.parent[e]];
        EXPECT_EQ(el.object, p.object);
        EXPECT_EQ(el.material, p.material);
        EXPECT_EQ(el.count, p.count);
        EXPECT_NEAR(glm::dot(el.normal, p.normal), 1.0, 1e-12);
        EXPECT_NEAR(glm::dot(el.centroid - p.centroid, p.normal), 0.0, 1e-12);
        EXPECT_LE(el.size, p.size / (split[r.parent[e]]) * (1 + 1e-12));
    }
    for (std::size_t i = 0; i < s.size(); ++i) {
        EXPECT_NEAR(area[i], s.patches[i].area, 1e-12 * s.patches[i].area) << i;
        EXPECT_EQ(count[i], std::size_t{split[i]} * split[i]) << i;
    }
    // Parents in patch order: the refined scene keeps the scene's order.
    EXPECT_TRUE(std::is_sorted(r.parent.begin(), r.parent.end()));
}

TEST(RefinePatches, GridsCoverThePatchesInOrderAndUntouchedGridsStayWhole) {
    const Scene s = quad_and_triangle();
    std::vector<std::uint32_t> split(s.size(), 1);
    split[0] = 2;  // only the floor's grid is touched
    const RefinedScene r = refine_patches(s, split);
    std::uint32_t next = 0;
    for (const PatchGrid& g : r.scene.grids) {
        EXPECT_EQ(g.first_patch, next);
        const std::uint32_t cells = g.count == 4 ? g.nu * g.nv : g.nu * g.nu;
        // The grid's corner c0 is the first cell's first vertex (the mesher's layout).
        EXPECT_EQ(r.scene.positions[r.scene.patches[g.first_patch].v[0]], g.corners[0]);
        next += cells;
    }
    EXPECT_EQ(next, r.scene.size());
    // The floor's grid became one grid per patch (4); the triangle's grid is kept as it was.
    ASSERT_EQ(r.scene.grids.size(), 4u + 1u);
    EXPECT_EQ(r.scene.grids.back().nu, s.grids.back().nu);
    EXPECT_EQ(r.scene.grids[0].nu, 2u);
    EXPECT_EQ(r.scene.grids[1].nu, 1u);
    // Nothing split: the same patches, grids and fingerprint.
    const RefinedScene same = refine_patches(s, std::vector<std::uint32_t>(s.size(), 1));
    EXPECT_EQ(same.scene.size(), s.size());
    EXPECT_EQ(same.scene.grids.size(), s.grids.size());
    EXPECT_EQ(same.scene.fingerprint, s.fingerprint);
}

}  // namespace
}  // namespace ffcube
