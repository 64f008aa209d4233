// Senders beside an occluder (issue 14, docs/accuracy.md "Senders beside an occluder"): a hemicube
// sees from the sender's centre, so where an occluder's silhouette sweeps across the sender the
// centre's visibility is not the sender's average visibility, and the unoccluded sender
// quadrature ratio cannot repair it. Ground cells beside a wall, with a taller wall behind it,
// have sky view factors known in closed form up to a smooth 1-D integral; the default correction
// must measure them as sub-hemicubes and get the mean within a bound derived below.
#include <gtest/gtest.h>

#include <glm/common.hpp>

#include <cmath>
#include <cstdio>
#include <numbers>

#include "ffcube/accuracy/near_field.hpp"
#include "ffcube/formfactor/sky.hpp"
#include "ffcube/geometry/analytic.hpp"
#include "ffcube/geometry/quadrature.hpp"
#include "ffcube/gl/hemicube_provider.hpp"
#include "ffcube/scene/mesher.hpp"
#include "ffcube/scene/polygons.hpp"

namespace ffcube {
namespace {

// Ground x ∈ [0, 4], y ∈ [−2, 2] (z = 0, facing up), meshed 1 × 1: 16 cells. Wall W at x = 0,
// height hW = 2, facing the ground (+x); wall V at x = −D = −2, height hV = 5, facing +x, behind
// W. Both walls span y ∈ [−2, 2]. Nothing else: what a cell does not see of W and V is sky.
constexpr double kHW = 2, kHV = 5, kD = 2, kHalf = 2;

Scene scene() {
    const std::vector<NamedPolygon> polys = {
        {"ground", {{0, -kHalf, 0}, {4, -kHalf, 0}, {4, kHalf, 0}, {0, kHalf, 0}}},
        {"w", {{0, -kHalf, 0}, {0, kHalf, 0}, {0, kHalf, kHW}, {0, -kHalf, kHW}}},
        {"v", {{-kD, -kHalf, 0}, {-kD, kHalf, 0}, {-kD, kHalf, kHV}, {-kD, -kHalf, kHV}}},
    };
    MeshOptions mo;
    mo.max_patch_edge = 1.0;
    return build_scene(model_from_polygons(polys, "<occluded senders test>"), mo);
}

// Point factor from p on the ground (normal +z) to what it sees of V: seen from p = (x, y, 0),
// W's top edge hides V below zc = hW (x + D) / x, over V's whole width (W's shadow on V's plane
// is W stretched by (x + D)/x ≥ 1 about p, so it covers V's y range). Exact (Lambert's contour).
double point_to_visible_v(double x, double y) {
    const double zc = kHW * (x + kD) / x;
    if (zc >= kHV) return 0;
    const std::vector<Vec3> rect = {{-kD, -kHalf, zc}, {-kD, kHalf, zc}, {-kD, kHalf, kHV}, {-kD, -kHalf, kHV}};
    return ff_point_polygon(Vec3(x, y, 0), Vec3(0, 0, 1), rect);
}

// Area average over the cell [x0, x1] × [y0, y1] of a function of the point, Gauss–Legendre
// 24 × 24, the x range split where V disappears behind W (x* = hW D / (hV − hW) = 4/3: the
// integrand has a kink there, smooth on each side): converged far below the bound used.
template <class F>
double cell_average(double x0, double x1, double y0, double y1, const F& f) {
    const GaussRule g = gauss_legendre(24);
    const double kink = kHW * kD / (kHV - kHW);
    std::vector<std::pair<double, double>> xs = {{x0, x1}};
    if (x0 < kink && kink < x1) xs = {{x0, kink}, {kink, x1}};
    double sum = 0;
    for (const auto& [a, b] : xs)
        for (std::size_t i = 0; i < g.x.size(); ++i)
            for (std::size_t j = 0; j < g.x.size(); ++j) {
                const double x = 0.5 * (a + b) + 0.5 * (b - a) * g.x[i];
                const double y = 0.5 * (y0 + y1) + 0.5 * (y1 - y0) * g.x[j];
                sum += 0.25 * (b - a) * (y1 - y0) * g.w[i] * g.w[j] * f(x, y);
            }
    return sum / ((x1 - x0) * (y1 - y0));
}

TEST(OccludedSenders, GroundBesideAWallWithAWallBehindGetsItsSkyViewFactor) {
    const Scene s = scene();
    ASSERT_EQ(s.size(), 16u + 8u + 20u);
    // Exact sky view factors of the ground cells: 1 − F(cell → W) − F(cell → visible part of V);
    // W is wholly visible from every cell (nothing stands between), F(cell → W) is the exact
    // polygon-to-polygon value.
    const std::vector<Vec3> w = {{0, -kHalf, 0}, {0, kHalf, 0}, {0, kHalf, kHW}, {0, -kHalf, kHW}};
    std::vector<std::uint32_t> ground;
    std::vector<double> exact;
    for (std::uint32_t i = 0; i < s.size(); ++i) {
        if (s.patches[i].normal.z < 0.5) continue;
        const auto v = s.patch_vertices(i);
        const std::vector<Vec3> cell(v.begin(), v.begin() + 4);
        Vec3 lo = cell[0], hi = cell[0];
        for (const Vec3& c : cell) {
            lo = glm::min(lo, c);
            hi = glm::max(hi, c);
        }
        ground.push_back(i);
        exact.push_back(1.0 - ff_polygon_polygon(cell, w) - cell_average(lo.x, hi.x, lo.y, hi.y, point_to_visible_v));
    }
    ASSERT_EQ(ground.size(), 16u);

    // Hemicube rows at N = 128 through the default correction, with and without the sampling of
    // senders beside occluders (the far field off, so that every ground row is measured).
    const int n = 128;
    double mean_error[2] = {0, 0};
    std::uint64_t occluder_rows[2] = {0, 0}, fine_rows[2] = {0, 0};
    for (const bool beside : {false, true}) {
        HemicubeOptions o;
        o.resolution = n;
        o.threads = 2;
        HemicubeRowProvider hemi(s, o);
        NearFieldOptions nf = near_field_options_for_hemicube(n);
        nf.far_field = NearFieldOptions::FarField::off;
        nf.sample_beside_occluders = beside;
        CorrectedRowProvider corrected(s, hemi, nf);
        RowLedger figures;
        const std::vector<double> sky = sky_view_factors(compute_all_rows(corrected, &figures));
        for (std::size_t k = 0; k < ground.size(); ++k) mean_error[beside] += (sky[ground[k]] - exact[k]) / 16.0;
        occluder_rows[beside] = corrected.stats().rows_sampled_occluder;
        fine_rows[beside] = corrected.stats().rows_sampled_fine;
        if (beside) {
            // The 4 cells touching W are measured at 4 × 4 points (W's box is within a cell size
            // of their centres), the 8 with W's cells within 3 sizes at 2 × 2, the last 4 at the
            // centre (W beyond the near range); per row in the report.
            const std::span<const std::int8_t> measure = figures.measures();
            for (std::size_t k = 0; k < ground.size(); ++k) {
                const auto& c = s.patches[ground[k]].centroid;
                EXPECT_EQ(measure[ground[k]], c.x < 1   ? CorrectedRowProvider::sampled_touching
                                              : c.x < 3 ? CorrectedRowProvider::sampled_occluder
                                                        : CorrectedRowProvider::centre)
                    << "cell at x = " << c.x;
            }
        }
    }
    // Without the option nothing is sampled for an occluder; with it, W's and V's rows may be too
    // (W hides part of the ground from V), so only the ground rows' measures are checked above.
    EXPECT_EQ(occluder_rows[0], 0u);
    EXPECT_EQ(fine_rows[0], 0u);
    EXPECT_GE(fine_rows[1], 4u);
    EXPECT_GE(occluder_rows[1], 8u);

    // The bound on the mean error with sub-hemicubes: (1) the quadrature rule's own error, the
    // 2 × 2 (4 × 4 beside W) Gauss rule applied to the exact point sky view factor (computed here
    // with the same point functions), averaged over the 12 sampled cells (the 4 at the centre see
    // V's lower edge move by ≤ 0.1 across them: their error is within (2)); plus (2) pixel noise
    // on the silhouette of W ∪ V against the sky, with the per-row noise model of the error
    // estimate (docs/accuracy.md): P = F/ΔF pixels have about 4√P outline pixels, each off by a
    // uniform share of ΔF = 4/(π (N/2)²) (σ = ΔF/√6), so σ_row = ΔF √(4√P/6) per sub-hemicube with
    // F ≤ 0.75 (W ≤ 0.5, V ≤ 0.25). The mean over 16 rows of ≥ 4 sub-hemicubes each, at rotated
    // frames and different points, divides it by √64; 4σ of that is the margin.
    double rule_error = 0;
    std::vector<Vec3> pts;
    std::vector<double> wts;
    for (std::size_t k = 0; k < ground.size(); ++k) {
        const auto v = s.patch_vertices(ground[k]);
        const std::vector<Vec3> cell(v.begin(), v.begin() + 4);
        const double x = s.patches[ground[k]].centroid.x;
        if (x > 3) continue;  // measured at the centre: its error is in (2)'s margin, see below
        patch_quadrature(cell, x < 1 ? 4 : 2, pts, wts);
        double q = 0;
        for (std::size_t m = 0; m < pts.size(); ++m)
            q += wts[m] * (1.0 - ff_point_polygon(pts[m], Vec3(0, 0, 1), w) - point_to_visible_v(pts[m].x, pts[m].y));
        rule_error += (q - exact[k]) / 16.0;
    }
    const double dff = 4.0 / (std::numbers::pi * (n / 2) * (n / 2));
    const double pixel = 4 * dff * std::sqrt(4 * std::sqrt(0.75 / dff) / 6) / std::sqrt(64.0);
    const double bound = std::abs(rule_error) + pixel;
    EXPECT_LT(std::abs(mean_error[1]), bound) << "rule error " << rule_error << ", pixel bound " << pixel;
    // And without the sampling the centre's visibility leaves a larger one-signed error.
    EXPECT_GT(std::abs(mean_error[0]), std::abs(mean_error[1]));
    std::printf("mean SVF error: centre %.3e, sub-hemicubes %.3e (bound %.3e: rule %.3e, pixels %.3e)\n",
                mean_error[0], mean_error[1], bound, rule_error, pixel);
}

}  // namespace
}  // namespace ffcube
