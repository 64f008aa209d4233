// Polygon basics against hand-computed values: Newell area and normal, area centroid,
// planarity, longest edge; far-off coordinates keep their precision.
#include "ffcube/geometry/polygon.hpp"

#include <glm/geometric.hpp>
#include <gtest/gtest.h>

#include <vector>

namespace ffcube {
namespace {

TEST(Polygon, AreaNormalCentroidOfAnLShape) {
    // L-shape: the unit-2 square minus its upper-right unit square, CCW seen from +z.
    // Area 3; centroid = mean of its three unit squares' centres.
    const std::vector<Vec3> ell = {{0, 0, 0}, {2, 0, 0}, {2, 1, 0}, {1, 1, 0}, {1, 2, 0}, {0, 2, 0}};
    EXPECT_NEAR(polygon_area(ell), 3.0, 1e-15);
    EXPECT_EQ(polygon_normal(ell), Vec3(0, 0, 1));
    const Vec3 c = polygon_centroid(ell);
    const Vec3 expected = (Vec3(0.5, 0.5, 0) + Vec3(1.5, 0.5, 0) + Vec3(0.5, 1.5, 0)) / 3.0;
    EXPECT_NEAR(glm::length(c - expected), 0.0, 1e-15);
    EXPECT_NEAR(polygon_max_edge(ell), 2.0, 1e-15);
    EXPECT_EQ(polygon_planarity_deviation(ell), 0.0);
}

TEST(Polygon, ClockwiseFlipsTheNormal) {
    const std::vector<Vec3> cw = {{0, 0, 0}, {0, 1, 0}, {1, 1, 0}, {1, 0, 0}};
    EXPECT_EQ(polygon_normal(cw), Vec3(0, 0, -1));
    EXPECT_NEAR(polygon_area(cw), 1.0, 1e-15);
}

TEST(Polygon, FarOffCoordinatesKeepPrecision) {
    // At 1e5 the input itself is rounded to ½ ulp = 7.3e-12, so each 1e-3 leg is known to
    // 7.3e-9 relative and the area to 1.5e-8; the Newell sum, taken relative to vertex 0,
    // adds nothing visible: 2e-8 relative. (From the origin it would lose everything.)
    const Vec3 o(1e5, -1e5, 1e5);
    const std::vector<Vec3> tri = {o, o + Vec3(1e-3, 0, 0), o + Vec3(0, 1e-3, 0)};
    EXPECT_NEAR(polygon_area(tri), 5e-7, 5e-7 * 2e-8);
}

TEST(Polygon, PlanarityDeviationAndDegenerates) {
    const std::vector<Vec3> bent = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0.2}, {0, 1, 0}};
    // Best-fit plane through the centroid along the Newell normal: the lifted vertex and its
    // opposite sit ±0.05 (×cos of the tilt) off it; the deviation is clearly non-zero and
    // below the lift.
    EXPECT_GT(polygon_planarity_deviation(bent), 0.01);
    EXPECT_LT(polygon_planarity_deviation(bent), 0.2);
    const std::vector<Vec3> line = {{0, 0, 0}, {1, 0, 0}, {2, 0, 0}};
    EXPECT_EQ(polygon_area(line), 0.0);
    EXPECT_EQ(polygon_normal(line), Vec3(0.0));
    const std::vector<Vec3> two = {{0, 0, 0}, {1, 0, 0}};
    EXPECT_EQ(polygon_area(two), 0.0);
}

}  // namespace
}  // namespace ffcube
