// The sub-hemicubes of a 4 × 4 row (RowPlan::sampled_fine) at N/2, 3N/8 or N/4
// (HemicubeOptions::fine_sub_resolution, --fine-sub-hemicubes; docs/accuracy.md, "Senders beside
// an occluder"): the resolutions chosen, each row against the closed form within its own derived
// pixel noise, and 2 × 2 rows untouched by the choice.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <map>
#include <numbers>
#include <vector>

#include "ffcube/geometry/analytic.hpp"
#include "ffcube/gl/hemicube_provider.hpp"
#include "gl/hemicube_worker.hpp"
#include "support/scenes.hpp"
#include "support/rows.hpp"

namespace ffcube {
namespace {

using Plan = RowProvider::RowPlan;
using Fine = HemicubeOptions::FineSubResolution;

SparseRow row_of(const Scene& scene, HemicubeOptions o, std::uint32_t p, Plan plan, HemicubeStats* stats = nullptr) {
    HemicubeRowProvider provider(scene, o);
    SparseRow out;
    const std::vector<std::uint32_t> rows{p};
    const std::vector<Plan> plans{plan};
    provider.compute_rows_planned(rows, plans, [&](std::uint32_t, const SparseRow& r) { out = r; });
    if (stats) *stats = provider.stats();
    return out;
}

using test::entry;

TEST(FineSubHemicubes, ResolutionsAreValidOrFallBackToHalf) {
    EXPECT_EQ(fine_resolution(128, Fine::half), 64);
    EXPECT_EQ(fine_resolution(128, Fine::three_eighths), 48);
    EXPECT_EQ(fine_resolution(128, Fine::quarter), 32);
    EXPECT_EQ(fine_resolution(256, Fine::three_eighths), 96);
    // N/4 = 4 and 3N/8 = 6 are below the smallest resolution (8): N/2 instead.
    EXPECT_EQ(fine_resolution(16, Fine::quarter), 8);
    EXPECT_EQ(fine_resolution(16, Fine::three_eighths), 8);
    // 3N/8 not whole (N = 20) or odd (N = 40: 15): N/2.
    EXPECT_EQ(fine_resolution(20, Fine::three_eighths), 10);
    EXPECT_EQ(fine_resolution(40, Fine::three_eighths), 20);
    EXPECT_EQ(fine_resolution(36, Fine::quarter), 18);  // N/4 = 9, odd
}

// A unit square sender on the ground (z = 0, facing up) and a unit square 2 above it (facing
// down): F = ff_parallel_rectangles(1, 1, 2) exactly, nothing occludes. A 4 × 4 row at n per
// sub-hemicube: the square's outline in each sub-hemicube (its image on the top face is n/4
// pixels square, an outline of n pixels; 4n as a bound, as in test_worker_range_limited.cpp) is
// wrongly in or out by at most ΔF_max = 4/(π n²) per pixel, uniform in ±½: σ ≤ √(4n) ΔF_max/√12
// per point, and √(Σ w²) = 1/4 of it for the 16 equal-weight points; asserted within 4σ. The rule's
// own error (the 4 × 4 Gauss rule on this smooth integrand) is below 1e-6, far below σ. By this
// bound the row's noise grows as n^(-3/2): N/4 has (64/32)^(3/2) = 2.8× the σ of N/2, 3N/8 has
// (64/48)^(3/2) = 1.5×.
TEST(FineSubHemicubes, EachResolutionIsWithinItsPixelNoiseOfTheClosedForm) {
    const std::vector<NamedPolygon> polys{
        {"sender", {{-0.5, -0.5, 0}, {0.5, -0.5, 0}, {0.5, 0.5, 0}, {-0.5, 0.5, 0}}},
        {"square", {{-0.5, -0.5, 2}, {-0.5, 0.5, 2}, {0.5, 0.5, 2}, {0.5, -0.5, 2}}},
    };
    const Scene scene = test::make_scene(polys, 1e9);
    const std::uint32_t sender = scene.patches[0].object == 0 ? 0 : 1, square = 1 - sender;
    const double exact = ff_parallel_rectangles(1, 1, 2);
    std::map<int, double> got;
    for (const Fine mode : {Fine::half, Fine::three_eighths, Fine::quarter}) {
        HemicubeOptions o;
        o.resolution = 128;
        o.threads = 1;
        o.fine_sub_resolution = mode;
        HemicubeStats st;
        const SparseRow r = row_of(scene, o, sender, Plan::sampled_fine, &st);
        EXPECT_EQ(st.hemicubes, 16u);
        const double n = fine_resolution(128, mode);
        const double sigma = std::sqrt(4 * n) * 4 / (std::numbers::pi * n * n) / std::sqrt(12.0) / 4;
        const double f = entry(r, square);
        EXPECT_NEAR(f, exact, 4 * sigma) << "n = " << n;
        got[static_cast<int>(n)] = f;
        std::printf("n = %d: F = %.6f, exact %.6f, error %+.1e (4 sigma %.1e)\n", static_cast<int>(n), f, exact,
                    f - exact, 4 * sigma);
    }
    // Three different rows: the option reaches the worker.
    EXPECT_NE(got[64], got[48]);
    EXPECT_NE(got[64], got[32]);
}

// 2 × 2 rows (RowPlan::sampled) stay at N/2 whatever the 4 × 4 rows use: bitwise the same row.
TEST(FineSubHemicubes, TwoByTwoRowsDoNotChange) {
    const Scene scene = test::make_scene(test::inward_box(1, 1, 1), 0.25);  // 16 patches a face
    HemicubeOptions o;
    o.resolution = 64;
    o.threads = 1;
    const SparseRow half = row_of(scene, o, 5, Plan::sampled);
    o.fine_sub_resolution = Fine::quarter;
    const SparseRow quarter = row_of(scene, o, 5, Plan::sampled);
    EXPECT_EQ(half.col, quarter.col);
    EXPECT_EQ(half.val, quarter.val);
}

}  // namespace
}  // namespace ffcube
