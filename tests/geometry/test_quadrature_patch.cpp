// patch_quadrature: the points and weights the sender quadrature and the sub-hemicubes share.
#include <gtest/gtest.h>

#include <vector>

#include "ffcube/geometry/quadrature.hpp"

namespace ffcube {
namespace {

double mean_of(const std::vector<Vec3>& poly, int n, double (*f)(const Vec3&)) {
    std::vector<Vec3> p;
    std::vector<double> w;
    patch_quadrature(poly, n, p, w);
    double s = 0, ws = 0;
    for (std::size_t k = 0; k < p.size(); ++k) {
        s += w[k] * f(p[k]);
        ws += w[k];
    }
    EXPECT_NEAR(ws, 1.0, 1e-15);
    return s;
}

// On a quad 2 × 2 Gauss is exact for x^a y^b with a, b ≤ 3 in the bilinear parameters times the
// Jacobian (degree 1 in each): a quadratic in x, y over a trapezoid is exact. Reference: the
// 8 × 8 rule (exact to rounding for it too). On a triangle the 3-point rule is exact for degree 2.
TEST(PatchQuadrature, ExactForLowDegreeOnQuadsAndTriangles) {
    const std::vector<Vec3> trapezoid{{0, 0, 1}, {3, 0, 1}, {2, 1, 1}, {0.5, 1, 1}};
    auto quad_f = [](const Vec3& x) { return x.x * x.x + 2 * x.x * x.y - x.y * x.y + x.z; };
    EXPECT_NEAR(mean_of(trapezoid, 2, quad_f), mean_of(trapezoid, 8, quad_f), 1e-13);
    const std::vector<Vec3> tri{{0, 0, 0}, {2, 0, 0}, {0.5, 1.5, 0}};
    EXPECT_NEAR(mean_of(tri, 2, quad_f), mean_of(tri, 8, quad_f), 1e-13);
    // A cubic is not exact with 3 points on a triangle: the test can fail.
    auto cubic = [](const Vec3& x) { return x.x * x.x * x.x; };
    EXPECT_GT(std::abs(mean_of(tri, 2, cubic) - mean_of(tri, 8, cubic)), 1e-3);
    // Points inside the patch (convex combinations): the quad's lie between its corners.
    std::vector<Vec3> p;
    std::vector<double> w;
    patch_quadrature(trapezoid, 2, p, w);
    ASSERT_EQ(p.size(), 4u);
    for (const Vec3& x : p) {
        EXPECT_GT(x.y, 0.0);
        EXPECT_LT(x.y, 1.0);
        EXPECT_DOUBLE_EQ(x.z, 1.0);
    }
}

}  // namespace
}  // namespace ffcube
