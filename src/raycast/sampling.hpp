// Internal to the raycast layer. One job: where the ray caster's rays go (a batch's strata, their
// cosine-weighted directions and the order they are cast in), apart from Embree and the rows.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <numbers>
#include <vector>

#include "ffcube/geometry/polygon.hpp"

namespace ffcube::raycast_sampling {

// sin and cos of t·π/4 for |t| ≤ 1: their Taylor series to the 15th and 16th power, whose first
// left-out terms are below 6e-17 on that range (within one ulp of std::sin and std::cos; checked
// by RaycastSampling.QuarterTurnSinCosIsTheLibrarys). A call to sincos cost as much as a ray's
// traversal once the rays came in coherent packets.
inline void sincos_quarter_turn(double t, double& s, double& c) {
    const double x = t * (std::numbers::pi / 4.0), x2 = x * x;
    s = x * (1.0 + x2 * (-1.0 / 6.0 + x2 * (1.0 / 120.0 + x2 * (-1.0 / 5040.0 + x2 * (1.0 / 362880.0 +
        x2 * (-1.0 / 39916800.0 + x2 * (1.0 / 6227020800.0 + x2 * (-1.0 / 1307674368000.0))))))));
    c = 1.0 + x2 * (-0.5 + x2 * (1.0 / 24.0 + x2 * (-1.0 / 720.0 + x2 * (1.0 / 40320.0 + x2 * (-1.0 / 3628800.0 +
        x2 * (1.0 / 479001600.0 + x2 * (-1.0 / 87178291200.0 + x2 * (1.0 / 20922789888000.0))))))));
}

// The concentric map (Shirley and Chiu 1997) of (r1, r2) on the unit square onto (x, y) on the
// unit disk, which keeps strata compact (the polar map would make wedges thin near the pole):
// φ = π/4 · b/a, or π/2 − π/4 · a/b (cos and sin swap), a quarter turn at most either way.
// Without branches (selects), so that make_rays' loop over a packet vectorizes. Lifted to the
// hemisphere, (x, y, √(1 − x² − y²)), it is the cosine-weighted direction (Malley).
inline void concentric_disk(double r1, double r2, double& x, double& y) {
    const double a = 2.0 * r1 - 1.0, b = 2.0 * r2 - 1.0;
    const bool wide = a * a > b * b;
    const double r = wide ? a : b, num = wide ? b : a;
    const double t = num / (r != 0.0 ? r : 1.0);  // r = 0 only at a = b = 0, where num = 0
    double sn = 0.0, cs = 0.0;
    sincos_quarter_turn(t, sn, cs);
    x = r * (wide ? cs : sn);
    y = r * (wide ? sn : cs);
}

// ---- The rays' samples: a 4-D Sobol' sequence, Owen-scrambled per row ----
//
// A ray is a point of [0,1)⁴: (r1, r2) its direction (concentric_disk, then lifted to the
// cosine-weighted hemisphere), (u, v) its origin on the sender. Row i's rays are the first R
// points of Sobol's sequence in those 4 dimensions (direction numbers of Joe and Kuo's
// new-joe-kuo-6.21201: x, then x + 1, x² + x + 1, x³ + x + 1), each dimension scrambled by a
// nested uniform (Owen) scramble seeded by the row (Laine and Karras's hash, as in Burley,
// "Practical Hash-based Owen Scrambling", JCGT 2020). Owen scrambling makes every point uniform
// on [0,1)⁴ (so a row is unbiased for any R) and keeps the net structure: the first 4^k points
// put exactly one point in each cell of a 2^k × 2^k grid of the direction square (dimensions 0
// and 1 form a (0,2)-sequence), the origins are as evenly spread, and, unlike stratifying the
// two projections apart and pairing them at random, the 4-D points are spread jointly, which is
// what a receiver near the sender, seen differently from each point, needs.

inline std::uint32_t reverse_bits(std::uint32_t x) {
    x = ((x >> 1) & 0x55555555u) | ((x & 0x55555555u) << 1);
    x = ((x >> 2) & 0x33333333u) | ((x & 0x33333333u) << 2);
    x = ((x >> 4) & 0x0F0F0F0Fu) | ((x & 0x0F0F0F0Fu) << 4);
    x = ((x >> 8) & 0x00FF00FFu) | ((x & 0x00FF00FFu) << 8);
    return (x >> 16) | (x << 16);
}

// Laine and Karras's permutation, with Vegdahl's constants ("Building a better LK hash", 2021:
// each output bit closer to an even coin flip over the seeds than the original's): bit j of the
// result depends on bits 0..j of x only (and the seed), so on bit-reversed input it is a nested
// uniform scramble.
inline std::uint32_t laine_karras(std::uint32_t x, std::uint32_t seed) {
    x ^= x * 0x3d20adeau;
    x += seed;
    x *= (seed >> 16) | 1u;
    x ^= x * 0x05526c56u;
    x ^= x * 0x53a22864u;
    return x;
}

// The direction numbers, bit-reversed: the Gray-code walk keeps each coordinate reversed, which
// is what the scramble takes.
struct SobolTable {
    std::uint32_t reversed[4][32];
    SobolTable() {
        struct Poly {
            int degree;
            unsigned inner;  // the coefficients a_1 .. a_{s−1}, a_1 the highest bit
            unsigned m[3];   // initial m_1 .. m_s
        };
        const Poly polys[3] = {{1, 0, {1, 0, 0}}, {2, 1, {1, 3, 0}}, {3, 1, {1, 3, 1}}};
        for (int j = 0; j < 32; ++j) reversed[0][j] = reverse_bits(1u << (31 - j));
        for (int d = 1; d < 4; ++d) {
            const Poly& p = polys[d - 1];
            std::uint64_t m[33] = {};
            for (int j = 1; j <= p.degree; ++j) m[j] = p.m[j - 1];
            for (int j = p.degree + 1; j <= 32; ++j) {
                std::uint64_t x = m[j - p.degree] ^ (m[j - p.degree] << p.degree);
                for (int k = 1; k < p.degree; ++k)
                    if ((p.inner >> (p.degree - 1 - k)) & 1u) x ^= m[j - k] << k;
                m[j] = x;
            }
            for (int j = 1; j <= 32; ++j) reversed[d][j - 1] = reverse_bits(static_cast<std::uint32_t>(m[j] << (32 - j)));
        }
    }
};

inline const SobolTable& sobol_table() {
    static const SobolTable table;
    return table;
}

// Points [first, first + count) of the unscrambled sequence into out, bit-reversed (4 words a
// point), walking the Gray code from point `first`, whose reversed coordinates `state` holds
// (all zero at point 0) and is left at point first + count. scramble() then makes them the
// points proper.
inline void sobol_walk(std::uint64_t first, std::uint32_t count, std::uint32_t state[4], std::uint32_t* __restrict out) {
    const SobolTable& t = sobol_table();
    std::uint32_t s0 = state[0], s1 = state[1], s2 = state[2], s3 = state[3];
    for (std::uint32_t k = 0; k < count; ++k) {
        const std::uint64_t index = first + k;
        if (index > 0) {
            const int bit = __builtin_ctzll(index);
            s0 ^= t.reversed[0][bit], s1 ^= t.reversed[1][bit], s2 ^= t.reversed[2][bit], s3 ^= t.reversed[3][bit];
        }
        out[4 * k] = s0, out[4 * k + 1] = s1, out[4 * k + 2] = s2, out[4 * k + 3] = s3;
    }
    state[0] = s0, state[1] = s1, state[2] = s2, state[3] = s3;
}

// Owen-scrambles n points (4 words each, as sobol_walk left them) in place: word w with seed[w %
// 4]. One loop over plain words, which the compiler vectorizes (see raycast_provider.cpp for the
// AVX2 copy); integer operations only, so every copy gives the same bits.
__attribute__((always_inline)) inline void scramble_body(std::uint32_t* __restrict words, std::size_t n,
                                                         const std::uint32_t seed[4]) {
    const std::uint32_t s0 = seed[0], s1 = seed[1], s2 = seed[2], s3 = seed[3];
    for (std::size_t k = 0; k < n; ++k) {
        std::uint32_t* w = words + 4 * k;
        w[0] = reverse_bits(laine_karras(w[0], s0));
        w[1] = reverse_bits(laine_karras(w[1], s1));
        w[2] = reverse_bits(laine_karras(w[2], s2));
        w[3] = reverse_bits(laine_karras(w[3], s3));
    }
}

// Points [first, first + count) of the scrambled sequence (4 words a point: r1, r2, u, v as
// 32-bit fractions); state as for sobol_walk. Plain copy (the tests').
inline void sobol_points(std::uint64_t first, std::uint32_t count, std::uint32_t state[4], const std::uint32_t seed[4],
                         std::uint32_t* out) {
    sobol_walk(first, count, state, out);
    scramble_body(out, count, seed);
}

// The cast order's key of direction cell (x, y) of a 2^b × 2^b grid: 4 × 4 tiles row after row
// of tiles, each tile's cells row after row (b < 2: row after row), so that the 16 rays of a
// packet leave in neighbouring directions and Embree's packet traversal
// (RTC_INTERSECT_CONTEXT_FLAG_COHERENT) visits the same nodes for most of them: half the CPU of
// single incoherent rays on a city. A bijection of the grid onto [0, 4^b).
inline std::uint32_t tile_key(std::uint32_t x, std::uint32_t y, int b) {
    if (b < 2) return (y << b) | x;
    return (((y >> 2) << (b - 2)) + (x >> 2)) * 16 + ((y & 3u) << 2) + (x & 3u);
}

}  // namespace ffcube::raycast_sampling
