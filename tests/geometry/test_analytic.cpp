// Analytic form factors checked against independent methods: textbook values, direct
// high-order quadrature of the defining area integral, Lambert's contour formula against the
// closed forms, superposition identities that hold exactly, reciprocity, and Monte Carlo.
#include "ffcube/reference/closed_forms.hpp"
#include "ffcube/geometry/quadrature.hpp"
#include "ffcube/core/error.hpp"
#include "ffcube/geometry/analytic.hpp"

#include <glm/geometric.hpp>
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <numbers>
#include <utility>
#include <vector>

namespace ffcube {
namespace {

constexpr double kPi = std::numbers::pi;


// The defining integral 1/A1 ∫∫ c² / (π r⁴) for parallel rectangles [x0,x1]×[y0,y1] (z = 0)
// and [u0,u1]×[v0,v1] (z = c), by a 4D Gauss product rule. The integrand is analytic with
// its nearest complex singularity at imaginary distance ≥ c from the real range, so for c of
// the order of the sizes the rule converges like ρ^(−2n), ρ ≈ 4 at n = 24: below rounding.
double parallel_rect_quadrature(double x0, double x1, double y0, double y1, double u0, double u1,
                                double v0, double v1, double c, int n) {
    const GaussRule g = gauss_legendre(n);
    const auto node = [&](double a, double b, int i) { return 0.5 * (a + b) + 0.5 * (b - a) * g.x[i]; };
    double sum = 0.0;
    for (int i = 0; i < n; ++i)
        for (int j = 0; j < n; ++j)
            for (int k = 0; k < n; ++k)
                for (int l = 0; l < n; ++l) {
                    const double dx = node(x0, x1, i) - node(u0, u1, k);
                    const double dy = node(y0, y1, j) - node(v0, v1, l);
                    const double r2 = dx * dx + dy * dy + c * c;
                    sum += g.w[i] * g.w[j] * g.w[k] * g.w[l] * c * c / (kPi * r2 * r2);
                }
    const double jac = (x1 - x0) * (y1 - y0) * (u1 - u0) * (v1 - v0) / 16.0;
    return sum * jac / ((x1 - x0) * (y1 - y0));
}

// Rectangle [x0,x1]×[y0,y1] in the plane z, facing +z (up) or −z (down), CCW from its front.
std::vector<Vec3> rect_z(double x0, double x1, double y0, double y1, double z, bool up) {
    if (up) return {{x0, y0, z}, {x1, y0, z}, {x1, y1, z}, {x0, y1, z}};
    return {{x0, y0, z}, {x0, y1, z}, {x1, y1, z}, {x1, y0, z}};
}

// Plate 2 hinged on the y axis (y ∈ [0,l]), at interior angle `alpha` to plate 1 (z = 0,
// x ∈ [0,w], facing +z), height h, facing plate 1.
std::vector<Vec3> hinged_plate(double l, double h, double alpha) {
    const Vec3 u(std::cos(alpha), 0.0, std::sin(alpha));
    return {{0, 0, 0}, {0, l, 0}, Vec3(0, l, 0) + h * u, h * u};
}

std::vector<Vec3> reversed(std::vector<Vec3> p) {
    std::reverse(p.begin(), p.end());
    return p;
}

std::vector<Vec3> transformed(const std::vector<Vec3>& p, double scale, const Vec3& offset) {
    std::vector<Vec3> out;
    for (const Vec3& v : p) out.push_back(scale * v + offset);
    return out;
}

// ---- closed forms ------------------------------------------------------------------------

TEST(ClosedForms, TextbookValues) {
    // Howell's catalog gives 5 decimals: the rounding bound is 5e-6.
    EXPECT_NEAR(ff_parallel_rectangles(1, 1, 1), 0.19982, 5e-6);
    EXPECT_NEAR(ff_perpendicular_rectangles_common_edge(1, 1, 1), 0.20004, 5e-6);
    // Coaxial disks r1 = r2 = h: X = 3, F = (3 − √5)/2 exactly.
    EXPECT_NEAR(ff_coaxial_disks(1, 1, 1), 0.5 * (3.0 - std::sqrt(5.0)), 1e-15);
}

TEST(ClosedForms, ParallelRectanglesMatchDirectQuadrature) {
    // The 4D Gauss rule (n = 24, error below 1e-15 by the analyticity bound above) is an
    // independent evaluation of the definition; the closed forms lose at most a few ulps to
    // cancellation in their brackets: 1e-13.
    EXPECT_NEAR(ff_parallel_rectangles(1, 1, 1), parallel_rect_quadrature(0, 1, 0, 1, 0, 1, 0, 1, 1, 24), 1e-13);
    EXPECT_NEAR(ff_parallel_rectangles(2, 0.5, 1.5),
                parallel_rect_quadrature(0, 2, 0, 0.5, 0, 2, 0, 0.5, 1.5, 24), 1e-13);
    EXPECT_NEAR(ff_parallel_rectangles_offset(0, 1, 0, 2, 0.5, 2.5, -1, 0.5, 1.2),
                parallel_rect_quadrature(0, 1, 0, 2, 0.5, 2.5, -1, 0.5, 1.2, 24), 1e-13);
}

TEST(ClosedForms, ParallelRectanglesFarAndThinKeepPrecision) {
    // Howell's bracket cancels to O(X²Y²) for far or thin rectangles; the regrouped form must
    // not. Far away the 4D Gauss reference converges even faster (ρ grows with c/size), so it
    // stays below rounding: compare relative to 1e-13.
    for (const auto& [a, b, c] : {std::array{1.0, 1.0, 100.0}, std::array{1.0, 1.0, 1000.0},
                                  std::array{1e-3, 1.0, 1.0}, std::array{0.3, 1e-3, 2.0}}) {
        const double ref = parallel_rect_quadrature(0, a, 0, b, 0, a, 0, b, c, 16);
        EXPECT_NEAR(ff_parallel_rectangles(a, b, c), ref, 1e-13 * ref) << a << " " << b << " " << c;
    }
    // Differential element to a far perpendicular rectangle (c = 1000, width 1, height 2):
    // reference by a 16×16 Gauss rule of the integrand z·c / (π (c²+y²+z²)²), smooth at this
    // distance (below rounding); the regrouped closed form must agree to rounding: 1e-13.
    const double c = 1000.0, width = 1.0, height = 2.0;
    const GaussRule g = gauss_legendre(16);
    double ref = 0.0;
    for (int i = 0; i < 16; ++i)
        for (int j = 0; j < 16; ++j) {
            const double y = 0.5 * width * (1.0 + g.x[i]), z = 0.5 * height * (1.0 + g.x[j]);
            const double r2 = c * c + y * y + z * z;
            ref += g.w[i] * g.w[j] * z * c / (kPi * r2 * r2);
        }
    ref *= 0.25 * width * height;
    EXPECT_NEAR(ff_diff_perpendicular_rect(width, height, c), ref, 1e-13 * ref);
}

TEST(ClosedForms, OffsetFormulaReducesToOpposedAndIsAdditive) {
    EXPECT_NEAR(ff_parallel_rectangles_offset(0, 2, 0, 3, 0, 2, 0, 3, 0.7), ff_parallel_rectangles(2, 3, 0.7), 1e-14);
    // Receiver additivity: splitting rectangle 2 in two splits F12 exactly.
    const double whole = ff_parallel_rectangles_offset(0, 1, 0, 1, -0.3, 1.4, 0.2, 1.1, 0.9);
    const double left = ff_parallel_rectangles_offset(0, 1, 0, 1, -0.3, 0.6, 0.2, 1.1, 0.9);
    const double right = ff_parallel_rectangles_offset(0, 1, 0, 1, 0.6, 1.4, 0.2, 1.1, 0.9);
    EXPECT_NEAR(whole, left + right, 1e-14);
    // Reciprocity A1 F12 = A2 F21 with the roles swapped.
    const double f12 = ff_parallel_rectangles_offset(0, 1, 0, 2, 3, 5, 1, 4, 2);
    const double f21 = ff_parallel_rectangles_offset(3, 5, 1, 4, 0, 1, 0, 2, 2);
    EXPECT_NEAR(2.0 * f12, 6.0 * f21, 1e-14);
}

TEST(ClosedForms, PerpendicularCommonEdgeReciprocity) {
    const double l = 1.3, w = 0.4, h = 2.1;
    EXPECT_NEAR(l * w * ff_perpendicular_rectangles_common_edge(l, w, h),
                l * h * ff_perpendicular_rectangles_common_edge(l, h, w), 1e-14);
}

TEST(ClosedForms, DifferentialElementsMatchLambert) {
    // Lambert's contour formula is exact and independent of the closed forms; both lose only
    // rounding: 1e-14.
    const Vec3 p(0, 0, 0), n(0, 0, 1);
    for (const auto& [a, b, c] : {std::array{1.0, 1.0, 1.0}, std::array{0.3, 2.0, 0.7}, std::array{5.0, 0.1, 0.2}}) {
        EXPECT_NEAR(ff_diff_parallel_rect(a, b, c), ff_point_polygon(p, n, rect_z(0, a, 0, b, c, false)), 1e-14);
        // Perpendicular rectangle in the plane x = c: width along y, height along z.
        const std::vector<Vec3> wall = {{c, 0, 0}, {c, 0, b}, {c, a, b}, {c, a, 0}};
        EXPECT_NEAR(ff_diff_perpendicular_rect(a, b, c), ff_point_polygon(p, n, wall), 1e-14);
    }
}

TEST(ClosedForms, CoaxialDisksMatchQuadratureAndPointLimit) {
    // Independent evaluation: F12 = 1/A1 ∫ 2πρ dρ ∫ r dr ∫ dφ h² / (π (h²+ρ²+r²−2ρr cosφ)²),
    // Gauss in ρ and r (analytic integrand for h of the order of the radii, n = 40 is below
    // rounding) and the trapezoid rule in the periodic φ (geometric convergence, 128 points).
    const double r1 = 0.8, r2 = 1.5, h = 1.1;
    const GaussRule g = gauss_legendre(40);
    const int m = 128;
    double sum = 0.0;
    for (int i = 0; i < 40; ++i) {
        const double rho = 0.5 * r1 * (1.0 + g.x[i]);
        for (int j = 0; j < 40; ++j) {
            const double r = 0.5 * r2 * (1.0 + g.x[j]);
            double ring = 0.0;
            for (int k = 0; k < m; ++k) {
                const double d2 = h * h + rho * rho + r * r - 2.0 * rho * r * std::cos(2.0 * kPi * k / m);
                ring += h * h / (kPi * d2 * d2);
            }
            sum += g.w[i] * g.w[j] * 2.0 * kPi * rho * r * ring * (2.0 * kPi / m);
        }
    }
    const double quad = sum * 0.25 * r1 * r2 / (kPi * r1 * r1);
    EXPECT_NEAR(ff_coaxial_disks(r1, r2, h), quad, 1e-13);
    // Reciprocity.
    EXPECT_NEAR(r1 * r1 * ff_coaxial_disks(r1, r2, h), r2 * r2 * ff_coaxial_disks(r2, r1, h), 1e-15);
    // A vanishing disk 1 tends to the point-to-disk value r2²/(h²+r2²), with an error O(R1²):
    // 1e-8 relative at R1 = 1e-4.
    EXPECT_NEAR(ff_coaxial_disks(1e-4, 1.0, 1.0), 0.5, 0.5 * 1e-8);
}

TEST(ClosedForms, ConcentricSpheres) {
    const SphereFactors f = ff_concentric_spheres(1.0, 2.0);
    EXPECT_EQ(f.f12, 1.0);
    EXPECT_DOUBLE_EQ(f.f21, 0.25);
    EXPECT_DOUBLE_EQ(f.f21 + f.f22, 1.0);
    // Reciprocity with sphere areas 4π r².
    EXPECT_DOUBLE_EQ(1.0 * f.f12, 4.0 * f.f21);
    EXPECT_THROW(ff_concentric_spheres(2.0, 1.0), InputError);
}

TEST(ClosedForms, RejectBadInput) {
    EXPECT_THROW(ff_parallel_rectangles(0, 1, 1), InputError);
    EXPECT_THROW(ff_coaxial_disks(1, 1, std::nan("")), InputError);
    EXPECT_THROW(ff_perpendicular_rectangles_common_edge(1, -1, 1), InputError);
    EXPECT_THROW(ff_parallel_rectangles_offset(1, 0, 0, 1, 0, 1, 0, 1, 1), InputError);
}

// ---- Lambert -----------------------------------------------------------------------------

TEST(PointPolygon, ClosedBoxSumsToOne) {
    // A point at the centre of a box's floor sees the ceiling and four walls: F sums to 1.
    const Vec3 p(0, 0, 0), n(0, 0, 1);
    const double a = 1.5, b = 0.7, c = 2.0;
    const std::vector<std::vector<Vec3>> faces = {
        rect_z(-a, a, -b, b, c, false),
        {{a, -b, 0}, {a, -b, c}, {a, b, c}, {a, b, 0}},
        {{-a, -b, 0}, {-a, b, 0}, {-a, b, c}, {-a, -b, c}},
        {{-a, b, 0}, {a, b, 0}, {a, b, c}, {-a, b, c}},
        {{-a, -b, 0}, {-a, -b, c}, {a, -b, c}, {a, -b, 0}},
    };
    double sum = 0.0;
    for (const auto& f : faces) sum += ff_point_polygon(p, n, f);
    EXPECT_NEAR(sum, 1.0, 1e-14);
}

TEST(PointPolygon, ClipsWhatIsBehindAndIgnoresOrientation) {
    const Vec3 p(0, 0, 0), n(0, 0, 1);
    // A wall in the plane x = 1 from z = −1 to 1: only the upper half counts, which is two
    // perpendicular rectangles (y ∈ [−1,0] and [0,1]) of Howell B-3.
    const std::vector<Vec3> wall = {{1, -1, -1}, {1, -1, 1}, {1, 1, 1}, {1, 1, -1}};
    const double expected = 2.0 * ff_diff_perpendicular_rect(1, 1, 1);
    EXPECT_NEAR(ff_point_polygon(p, n, wall), expected, 1e-14);
    EXPECT_NEAR(ff_point_polygon(p, n, reversed(wall)), expected, 1e-14);
    // Entirely behind: nothing.
    EXPECT_EQ(ff_point_polygon(p, n, rect_z(-1, 1, -1, 1, -0.5, true)), 0.0);
    // A point in the polygon's plane sees it edge-on.
    EXPECT_EQ(ff_point_polygon(Vec3(0, 0, 1), Vec3(1, 0, 0), rect_z(0, 1, 0, 1, 1, false)), 0.0);
}

TEST(PointPolygon, RejectsBadPolygons) {
    const Vec3 p(0, 0, 0), n(0, 0, 1);
    const std::vector<Vec3> two = {{0, 0, 1}, {1, 0, 1}};
    EXPECT_THROW(ff_point_polygon(p, n, two), InputError);
    const std::vector<Vec3> bent = {{0, 0, 1}, {1, 0, 1}, {1, 1, 1.1}, {0, 1, 1}};
    EXPECT_THROW(ff_point_polygon(p, n, bent), InputError);
    EXPECT_THROW(ff_point_polygon(p, Vec3(0), rect_z(0, 1, 0, 1, 1, false)), InputError);
}

// ---- polygon to polygon ------------------------------------------------------------------

// The contour integral is exact up to the adaptive quadrature (tolerance 1e-13 per edge pair,
// times the 16–25 pairs here) and rounding: comparisons with closed forms use 1e-11, two
// orders above the quadrature bound and far below the 1e-9 the brief asks for.
constexpr double kContourTol = 1e-11;

TEST(PolygonPolygon, OpposedParallelSquares) {
    const auto p1 = rect_z(0, 1, 0, 1, 0, true), p2 = rect_z(0, 1, 0, 1, 1, false);
    EXPECT_NEAR(ff_polygon_polygon(p1, p2), ff_parallel_rectangles(1, 1, 1), kContourTol);
    EXPECT_NEAR(ff_polygon_polygon(p1, p2), 0.19982, 5e-6);
    const auto q1 = rect_z(0, 2, 0, 0.5, 0, true), q2 = rect_z(0, 2, 0, 0.5, 0.25, false);
    EXPECT_NEAR(ff_polygon_polygon(q1, q2), ff_parallel_rectangles(2, 0.5, 0.25), kContourTol);
}

TEST(PolygonPolygon, ParallelRectanglesWithOffsets) {
    const auto p1 = rect_z(0, 1, 0, 2, 0, true), p2 = rect_z(0.5, 2.5, -1, 0.5, 1.2, false);
    EXPECT_NEAR(ff_polygon_polygon(p1, p2), ff_parallel_rectangles_offset(0, 1, 0, 2, 0.5, 2.5, -1, 0.5, 1.2), kContourTol);
    // Far apart sideways (offset 10 sizes): F ~ 1e-4, still to 1e-11 absolute.
    const auto p3 = rect_z(10, 11, 0, 1, 1, false);
    EXPECT_NEAR(ff_polygon_polygon(rect_z(0, 1, 0, 1, 0, true), p3),
                ff_parallel_rectangles_offset(0, 1, 0, 1, 10, 11, 0, 1, 1), kContourTol);
}

TEST(PolygonPolygon, PerpendicularCommonEdge) {
    const auto p1 = rect_z(0, 1, 0, 1, 0, true), p2 = hinged_plate(1, 1, kPi / 2);
    EXPECT_NEAR(ff_polygon_polygon(p1, p2), ff_perpendicular_rectangles_common_edge(1, 1, 1), kContourTol);
    EXPECT_NEAR(ff_polygon_polygon(p1, p2), 0.20004, 5e-6);
    // Unequal sides, both directions.
    const double l = 1.3, w = 0.4, h = 2.1;
    const auto q1 = rect_z(0, w, 0, l, 0, true), q2 = hinged_plate(l, h, kPi / 2);
    EXPECT_NEAR(ff_polygon_polygon(q1, q2), ff_perpendicular_rectangles_common_edge(l, w, h), kContourTol);
    EXPECT_NEAR(ff_polygon_polygon(q2, q1), ff_perpendicular_rectangles_common_edge(l, h, w), kContourTol);
}

TEST(PolygonPolygon, FarApartAndSmallAgainstQuadrature) {
    // Far apart or very unequal, the Lambert-over-the-smaller-polygon path is used; the 4D
    // Gauss reference is then analytic with far singularities (below rounding at n = 16), and
    // both agree to rounding amplified by at most log10(D/L) digits: 1e-12 relative.
    const auto p1 = rect_z(0, 1, 0, 1, 0, true);
    for (double d : {10.0, 100.0, 1000.0}) {
        const double ref = parallel_rect_quadrature(0, 1, 0, 1, 0.3, 1.5, -0.2, 0.6, d, 16);
        EXPECT_NEAR(ff_polygon_polygon(p1, rect_z(0.3, 1.5, -0.2, 0.6, d, false)), ref, 1e-12 * ref) << d;
    }
    // Size ratio 1:1e4, both directions (reciprocity: A1 F12 = A2 F21).
    const double s = 1e-4;
    const double small_to_big = parallel_rect_quadrature(0, s, 0, s, 0, 1, 0, 1, 1, 16);
    EXPECT_NEAR(ff_polygon_polygon(rect_z(0, s, 0, s, 0, true), rect_z(0, 1, 0, 1, 1, false)), small_to_big,
                1e-12 * small_to_big);
    EXPECT_NEAR(ff_polygon_polygon(rect_z(0, 1, 0, 1, 1, false), rect_z(0, s, 0, s, 0, true)),
                small_to_big * s * s, 1e-12 * small_to_big * s * s);
}

TEST(PolygonPolygon, SharedVertexBySuperposition) {
    // Square 1 = [0,1]² in z = 0; square 2 in the plane x = 0 over y ∈ [−1,0], z ∈ [0,1]: they
    // touch at the origin only. With the mirror images this is a common-edge pair of 2×1
    // plates, so F(vertex) = F_ce(l=2, w=1, h=1) − F_ce(l=1, w=1, h=1), exactly.
    const auto p1 = rect_z(0, 1, 0, 1, 0, true);
    const std::vector<Vec3> p2 = {{0, -1, 0}, {0, 0, 0}, {0, 0, 1}, {0, -1, 1}};
    const double expected = ff_perpendicular_rectangles_common_edge(2, 1, 1) -
                            ff_perpendicular_rectangles_common_edge(1, 1, 1);
    EXPECT_NEAR(ff_polygon_polygon(p1, p2), expected, kContourTol);
}

TEST(PolygonPolygon, NearlyTouching) {
    // Perpendicular plate lifted by a gap g = 1e-3: by receiver additivity,
    // F = F_ce(1, 1, 1+g) (plate reaching down to the edge) − F_ce(1, 1, g) (the missing strip).
    const double g = 1e-3;
    const auto p1 = rect_z(0, 1, 0, 1, 0, true);
    const std::vector<Vec3> p2 = {{0, 0, g}, {0, 1, g}, {0, 1, 1 + g}, {0, 0, 1 + g}};
    const double expected = ff_perpendicular_rectangles_common_edge(1, 1, 1 + g) -
                            ff_perpendicular_rectangles_common_edge(1, 1, g);
    EXPECT_NEAR(ff_polygon_polygon(p1, p2), expected, kContourTol);
    // Parallel plates 1e-3 apart: F close to 1.
    EXPECT_NEAR(ff_polygon_polygon(p1, rect_z(0, 1, 0, 1, g, false)), ff_parallel_rectangles(1, 1, g), kContourTol);
}

TEST(PolygonPolygon, TrianglesBySymmetry) {
    // A diagonal halves square 1 into triangles that are images of each other under the
    // half-turn about the axis through both squares' centres, which maps square 2 to itself:
    // each triangle sees square 2 like the square does, and square 1 sees each of square 2's
    // triangles with half of its F.
    const auto sq1 = rect_z(0, 1, 0, 1, 0, true), sq2 = rect_z(0, 1, 0, 1, 1, false);
    const std::vector<Vec3> tri1 = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}};
    const std::vector<Vec3> tri2 = {{0, 0, 1}, {1, 1, 1}, {1, 0, 1}};
    const double f = ff_parallel_rectangles(1, 1, 1);
    EXPECT_NEAR(ff_polygon_polygon(tri1, sq2), f, kContourTol);
    EXPECT_NEAR(ff_polygon_polygon(sq1, tri2), 0.5 * f, kContourTol);
}

TEST(PolygonPolygon, NonConvexPolygon) {
    // An L-shaped receiver = union of two rectangles (additivity).
    const auto p1 = rect_z(0, 1, 0, 1, 0, true);
    const std::vector<Vec3> ell = {{-0.5, -0.5, 0.8}, {-0.5, 1.5, 0.8}, {0.5, 1.5, 0.8},
                                   {0.5, 0.5, 0.8},   {1.5, 0.5, 0.8},  {1.5, -0.5, 0.8}};
    const double expected = ff_parallel_rectangles_offset(0, 1, 0, 1, -0.5, 0.5, -0.5, 1.5, 0.8) +
                            ff_parallel_rectangles_offset(0, 1, 0, 1, 0.5, 1.5, -0.5, 0.5, 0.8);
    EXPECT_NEAR(ff_polygon_polygon(p1, ell), expected, kContourTol);
}

TEST(PolygonPolygon, ClipsBehindAndFacingAway) {
    const auto p1 = rect_z(0, 1, 0, 1, 0, true);
    // A perpendicular plate reaching below plate 1's plane: only z ≥ 0 counts.
    const std::vector<Vec3> through = {{0, 0, -1}, {0, 1, -1}, {0, 1, 1}, {0, 0, 1}};
    EXPECT_NEAR(ff_polygon_polygon(p1, through), ff_perpendicular_rectangles_common_edge(1, 1, 1), kContourTol);
    // Plate 2 facing away (its back towards plate 1): it receives nothing on its front.
    EXPECT_EQ(ff_polygon_polygon(p1, rect_z(0, 1, 0, 1, 1, true)), 0.0);
    // Plate 2 entirely behind plate 1.
    EXPECT_EQ(ff_polygon_polygon(p1, rect_z(0, 1, 0, 1, -1, true)), 0.0);
    // Coplanar neighbours exchange nothing.
    EXPECT_EQ(ff_polygon_polygon(p1, rect_z(1, 2, 0, 1, 0, true)), 0.0);
}

TEST(PolygonPolygon, ReciprocityAtAnAngle) {
    // No closed form is used here: A1 F12 = A2 F21 checks the two contour evaluations (which
    // integrate different edges in closed form) against each other.
    const double l = 1.0, w = 0.6, h = 1.7, alpha = 2.0 * kPi / 3.0;
    const auto p1 = rect_z(0, w, 0, l, 0, true), p2 = hinged_plate(l, h, alpha);
    EXPECT_NEAR(w * l * ff_polygon_polygon(p1, p2), h * l * ff_polygon_polygon(p2, p1), kContourTol);
}

TEST(PolygonPolygon, InvariantUnderTranslationAndScale) {
    // Shifting to polygon 1's centroid and scaling to unit size happen before any arithmetic
    // that matters; what is left is the rounding of the input coordinates themselves
    // (1e5 × 1e-16 = 1e-11 of a unit-size polygon), so 1e-10 relative.
    const auto p1 = rect_z(0, 1, 0, 1, 0, true), p2 = hinged_plate(1, 1, kPi / 3);
    const double f = ff_polygon_polygon(p1, p2);
    for (const auto& [s, off] : {std::pair{1.0, Vec3(1e5, -1e5, 1e5)}, std::pair{1e-4, Vec3(0.3, 0, 0)},
                                 std::pair{1e4, Vec3(0, 2e4, 0)}}) {
        EXPECT_NEAR(ff_polygon_polygon(transformed(p1, s, off), transformed(p2, s, off)), f, 1e-10 * f);
    }
}

TEST(PolygonPolygon, MatchesMonteCarlo) {
    // 1e6 cosine-distributed rays: the hit fraction is binomial, standard error
    // σ = √(F(1−F)/n) ≈ 4e-4. 5σ keeps a fixed-seed test from flaking under any seed
    // (two-sided 5σ: 6e-7) while a sign or clipping error (≥ 1e-2) fails it.
    const std::uint64_t n = 1'000'000;
    const auto check = [n](const std::vector<Vec3>& a, const std::vector<Vec3>& b, std::uint64_t seed) {
        const double exact = ff_polygon_polygon(a, b);
        const double sigma = std::sqrt(exact * (1.0 - exact) / static_cast<double>(n));
        EXPECT_NEAR(ff_polygon_polygon_mc(a, b, n, seed), exact, 5.0 * sigma);
    };
    check(rect_z(0, 1, 0, 1, 0, true), hinged_plate(1, 1, kPi / 3), 1);          // 60°, shared edge
    check(rect_z(0, 0.6, 0, 1, 0, true), hinged_plate(1, 1.7, 2 * kPi / 3), 2);  // 120°
    const std::vector<Vec3> tri1 = {{0, 0, 0}, {1, 0.2, 0}, {0.3, 1, 0}};
    const std::vector<Vec3> tri2 = {{0.2, 0.1, 0.5}, {-0.4, 0.9, 0.9}, {1.1, 0.6, 0.7}};
    check(tri1, tri2, 3);  // two triangles in general position
}

}  // namespace
}  // namespace ffcube

namespace ffcube {
namespace {

// A box's wall and ceiling patches as the mesher rounds them: the ceiling's vertices are an ulp
// or two below z = 1, so the wall's top edge lies 1e-16 behind the ceiling's plane and clipping
// leaves a sliver 1e-16 thick. The adaptive quadrature used to bisect rounding noise in both
// halves at every level (2^50 evaluations, never returning). It must now return, and agree with
// the same pair with the ceiling exactly at z = 1: moving vertices by 2.2e-16 changes F by
// O(1e-15) relative, so 1e-12 leaves room for the quadrature tolerance (1e-13 per edge pair).
TEST(PolygonPolygon, SliverClippedByRoundingReturnsTheUnroundedValue) {
    const std::vector<Vec3> wall = {{0, 0.58333333333333337, 0.91666666666666663},
                                    {0, 0.66666666666666663, 0.91666666666666663},
                                    {0, 0.66666666666666663, 1},
                                    {0, 0.58333333333333337, 1}};
    const std::vector<Vec3> rounded = {{0.083333333333333329, 0.41666666666666663, 0.99999999999999978},
                                       {0.083333333333333329, 0.5, 0.99999999999999989},
                                       {0.16666666666666666, 0.5, 1},
                                       {0.16666666666666666, 0.41666666666666674, 0.99999999999999989}};
    std::vector<Vec3> exact = rounded;
    for (Vec3& v : exact) v.z = 1.0;
    const double f = ff_polygon_polygon(wall, rounded);
    const double ref = ff_polygon_polygon(wall, exact);
    EXPECT_GT(ref, 0.0);
    EXPECT_NEAR(f, ref, 1e-12 * ref);
}

}  // namespace
}  // namespace ffcube

namespace ffcube {
namespace {

// The unclipped fast path equals the checked one wherever its precondition holds: quads and
// triangles wholly in front of the point's plane, at several distances and orientations.
TEST(PointPolygon, PointPolygonFastPathAgrees) {
    const Vec3 n = glm::normalize(Vec3(0.2, -0.3, 1.0));
    int compared = 0;
    for (int k = 0; k < 200; ++k) {
        const double a = 0.1 * k, d = 0.05 + 0.02 * k;
        const Vec3 c = Vec3(std::cos(a), std::sin(1.3 * a), 0.0) + n * (0.5 + d);
        const Vec3 u = glm::normalize(Vec3(std::cos(0.7 * a), 0.3, std::sin(0.7 * a)));
        const Vec3 v = glm::normalize(glm::cross(u, Vec3(0.1, 1.0, 0.2)));
        const std::vector<Vec3> quad{c, c + 0.3 * u, c + 0.3 * u + 0.2 * v, c + 0.2 * v};
        const std::vector<Vec3> tri{c, c + 0.3 * u, c + 0.2 * v};
        for (const auto* poly : {&quad, &tri}) {
            bool in_front = true;
            for (const Vec3& x : *poly) in_front = in_front && glm::dot(x, n) > 0;
            if (!in_front) continue;
            const double slow = ff_point_polygon(Vec3(0.0), n, *poly);
            EXPECT_NEAR(ff_point_polygon_unclipped(Vec3(0.0), n, *poly), slow, 1e-14 + 1e-12 * slow) << k;
            ++compared;
        }
    }
    EXPECT_GT(compared, 300);
}

}  // namespace
}  // namespace ffcube
