// The ray caster's sampling helpers (src/raycast/sampling.hpp), on their own: the quarter-turn
// sin and cos against the library's, the concentric map onto the disk, and the order a
// batch's direction strata are cast in.
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <set>
#include <vector>

#include "raycast/sampling.hpp"

namespace ffcube {
namespace {

using namespace raycast_sampling;

// The Taylor series to x^15 and x^16 on |x| ≤ π/4: the first left-out terms are
// (π/4)^17/17! < 6e-17 and (π/4)^18/18! < 3e-18, so with Horner's rounding (a few half-ulps of
// values ≤ 1) both are within 2 ulp of 1.0 (4.4e-16) of the correctly rounded values; glibc's
// sin and cos are within 1 ulp. Asserted: 4.5e-16 over 2 million points and the ends.
TEST(RaycastSampling, QuarterTurnSinCosIsTheLibrarys) {
    double worst_s = 0.0, worst_c = 0.0;
    for (int k = -1000000; k <= 1000000; ++k) {
        const double t = k / 1e6, x = t * std::numbers::pi / 4.0;
        double s = 0.0, c = 0.0;
        sincos_quarter_turn(t, s, c);
        worst_s = std::max(worst_s, std::abs(s - std::sin(x)));
        worst_c = std::max(worst_c, std::abs(c - std::cos(x)));
    }
    EXPECT_LT(worst_s, 4.5e-16);
    EXPECT_LT(worst_c, 4.5e-16);
    double s = 0.0, c = 0.0;
    sincos_quarter_turn(1.0, s, c);
    EXPECT_NEAR(s, std::sqrt(0.5), 4.5e-16);
    EXPECT_NEAR(c, std::sqrt(0.5), 4.5e-16);
}

// The concentric map takes the square's border to the unit circle and its centre to the disk's
// centre; it is Shirley and Chiu's polar point (r, φ), which std::cos and std::sin give
// independently (with branches, as they wrote it); and its lift √(1 − x² − y²) is real.
TEST(RaycastSampling, ConcentricDiskIsShirleyAndChiusMap) {
    double x = 1.0, y = 1.0;
    concentric_disk(0.5, 0.5, x, y);
    EXPECT_EQ(x, 0.0);
    EXPECT_EQ(y, 0.0);
    for (int i = 0; i <= 40; ++i)
        for (int j = 0; j <= 40; ++j) {
            const double r1 = i / 40.0, r2 = j / 40.0;
            concentric_disk(r1, r2, x, y);
            const double a = 2 * r1 - 1, b = 2 * r2 - 1;
            double r = 0, phi = 0;
            if (a * a > b * b) {
                r = a, phi = std::numbers::pi / 4 * (b / a);
            } else if (b != 0) {
                r = b, phi = std::numbers::pi / 2 - std::numbers::pi / 4 * (a / b);
            }
            EXPECT_NEAR(x, r * std::cos(phi), 1e-15);
            EXPECT_NEAR(y, r * std::sin(phi), 1e-15);
            EXPECT_LE(x * x + y * y, 1.0 + 4e-16);
            if (i == 0 || i == 40 || j == 0 || j == 40) {
                EXPECT_NEAR(x * x + y * y, 1.0, 4e-16);
            }
        }
}

// tile_order lists every stratum of the m × m batch once, and each run of 16 consecutive strata
// (a packet) lies within one 4 × 4 tile when m is a multiple of 4; for other m, within a tile
// clipped at the edge, so a packet may span two of those but never leaves a 4-row band.
TEST(RaycastSampling, TileOrderIsAPermutationInFourByFourTiles) {
    for (std::uint32_t m : {1u, 3u, 4u, 7u, 16u, 181u, 256u}) {
        std::vector<std::uint32_t> order;
        tile_order(m, order);
        ASSERT_EQ(order.size(), static_cast<std::size_t>(m) * m);
        EXPECT_EQ(std::set<std::uint32_t>(order.begin(), order.end()).size(), order.size());
        for (std::size_t k = 0; k + 16 <= order.size(); k += 16) {
            std::uint32_t xmin = m, xmax = 0, ymin = m, ymax = 0;
            for (std::size_t l = k; l < k + 16; ++l) {
                const std::uint32_t x = stratum_x(order[l]), y = stratum_y(order[l]);
                ASSERT_LT(x, m);
                ASSERT_LT(y, m);
                xmin = std::min(xmin, x), xmax = std::max(xmax, x);
                ymin = std::min(ymin, y), ymax = std::max(ymax, y);
            }
            if (m % 4 == 0) {
                EXPECT_EQ(xmin / 4, xmax / 4) << "m " << m << " packet " << k / 16;
                EXPECT_EQ(ymin / 4, ymax / 4) << "m " << m << " packet " << k / 16;
            } else {
                EXPECT_LE(ymax - ymin, 7u) << "m " << m << " packet " << k / 16;
            }
        }
    }
}

}  // namespace
}  // namespace ffcube
