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

// tile_key is a bijection of the 2^b × 2^b direction grid onto [0, 4^b), and the 16 cells of
// each run of 16 consecutive keys (a packet) lie in one 4 × 4 tile.
TEST(RaycastSampling, TileKeysAreAPermutationInFourByFourTiles) {
    for (int b : {0, 1, 2, 3, 8}) {
        const std::uint32_t side = 1u << b;
        std::vector<std::pair<std::uint32_t, std::uint32_t>> cell(static_cast<std::size_t>(side) * side, {side, side});
        for (std::uint32_t y = 0; y < side; ++y)
            for (std::uint32_t x = 0; x < side; ++x) {
                const std::uint32_t k = tile_key(x, y, b);
                ASSERT_LT(k, cell.size());
                ASSERT_EQ(cell[k].first, side) << "key " << k << " given twice";
                cell[k] = {x, y};
            }
        if (b < 2) continue;
        for (std::size_t k = 0; k < cell.size(); k += 16)
            for (std::size_t l = k; l < k + 16; ++l) {
                EXPECT_EQ(cell[l].first / 4, cell[k].first / 4) << "b " << b << " packet " << k / 16;
                EXPECT_EQ(cell[l].second / 4, cell[k].second / 4) << "b " << b << " packet " << k / 16;
            }
    }
}

// The scrambled Sobol' points. Unscrambled (seed 0 is not the identity, so the raw sequence is
// checked through the table): dimension 0 is van der Corput's sequence, dimensions 1–3 follow
// Joe and Kuo's recurrences (v_3 = 5/8, 3/8, 1/8 from m = 1, 3, 5; 1, 3, 3; 1, 3, 1). Scrambled with any seeds: the first 4^k points put exactly
// one point in each cell of a 2^k × 2^k grid of the direction square (dimensions 0, 1), the
// origins (dimensions 2, 3) at most 2 a cell, and the 4-D points are a net: every box of 2^a ×
// 2^b × 2^c × 2^d cells with a + b + c + d = 2k − t holds exactly 2^t points (t = 3 for these
// four dimensions, as Joe and Kuo's table gives for the first four); and a chunk walked from
// point `first` continues the walk from 0 exactly.
TEST(RaycastSampling, SobolPointsAreScrambledNets) {
    const SobolTable& t = sobol_table();
    // Point n of the unscrambled sequence in natural order (sobol_points walks the Gray code:
    // the same set of points in each aligned block of 2^j).
    const auto raw = [&](std::uint32_t n, int d) {
        std::uint32_t x = 0;
        for (std::uint32_t j = 0; n; n >>= 1, ++j)
            if (n & 1u) x ^= t.reversed[d][j];
        return reverse_bits(x) * 0x1.0p-32;
    };
    const double expected[5][4] = {{0, 0, 0, 0},
                                   {0.5, 0.5, 0.5, 0.5},
                                   {0.25, 0.75, 0.75, 0.75},
                                   {0.75, 0.25, 0.25, 0.25},
                                   {0.125, 0.625, 0.375, 0.125}};
    for (std::uint32_t n = 0; n < 5; ++n)
        for (int d = 0; d < 4; ++d) EXPECT_EQ(raw(n, d), expected[n][d]) << "point " << n << " dimension " << d;
    for (const std::uint32_t s0 : {0u, 12345u, 0xdeadbeefu}) {
        const std::uint32_t seed[4] = {s0, s0 * 3 + 1, s0 ^ 0x9e3779b9u, s0 + 77};
        const int k = 6;
        const std::uint32_t n = 1u << (2 * k);
        std::vector<std::uint32_t> p(4 * n);
        std::uint32_t state[4] = {0, 0, 0, 0};
        sobol_points(0, n / 2, state, seed, p.data());
        sobol_points(n / 2, n / 2, state, seed, p.data() + 2 * n);
        std::vector<std::uint32_t> whole(4 * n);
        std::uint32_t fresh[4] = {0, 0, 0, 0};
        sobol_points(0, n, fresh, seed, whole.data());
        EXPECT_EQ(p, whole);
        std::vector<int> dir(n, 0), org(n, 0);
        for (std::uint32_t q = 0; q < n; ++q) {
            ++dir[(p[4 * q] >> (32 - k)) << k | (p[4 * q + 1] >> (32 - k))];
            ++org[(p[4 * q + 2] >> (32 - k)) << k | (p[4 * q + 3] >> (32 - k))];
        }
        EXPECT_EQ(*std::min_element(dir.begin(), dir.end()), 1);
        EXPECT_EQ(*std::max_element(dir.begin(), dir.end()), 1);
        EXPECT_LE(*std::max_element(org.begin(), org.end()), 2);
        const int m = 2 * k, tq = 3;
        for (int a = 0; a <= m - tq; ++a)
            for (int b = 0; a + b <= m - tq; ++b)
                for (int c = 0; a + b + c <= m - tq; ++c) {
                    const int d = m - tq - a - b - c;
                    std::vector<int> box(std::size_t{1} << (m - tq), 0);
                    for (std::uint32_t q = 0; q < n; ++q) {
                        const auto top = [&](int dim, int bits) { return bits ? p[4 * q + dim] >> (32 - bits) : 0u; };
                        ++box[(((top(0, a) << b | top(1, b)) << c | top(2, c)) << d) | top(3, d)];
                    }
                    for (const int v : box) ASSERT_EQ(v, 1 << tq) << a << b << c << d << " seed " << s0;
                }
    }
}

}  // namespace
}  // namespace ffcube
