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

// The side m of a batch's m × m strata for `left` rays still to cast: ⌊√left⌋, at most
// kMaxStrataSide (so a batch's permutation holds at most 65,536 entries, whatever --rays is).
inline constexpr std::uint64_t kMaxStrataSide = 256;
inline std::uint64_t strata_side(std::uint64_t left) {
    std::uint64_t m = static_cast<std::uint64_t>(std::sqrt(static_cast<double>(left)));
    while (m * m > left) --m;
    while ((m + 1) * (m + 1) <= left) ++m;
    return std::clamp<std::uint64_t>(m, 1, kMaxStrataSide);
}

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

// A stratum (x, y) of an m × m grid, m ≤ kMaxStrataSide, packed in one word: no division by m
// to unpack it (four of them a ray cost as much as the shuffle).
inline std::uint32_t pack_stratum(std::uint32_t x, std::uint32_t y) { return x | (y << 16); }
inline std::uint32_t stratum_x(std::uint32_t s) { return s & 0xFFFFu; }
inline std::uint32_t stratum_y(std::uint32_t s) { return s >> 16; }

// The direction strata of an m × m batch (packed) in the order its rays are cast: 4 × 4 tiles of the
// square, row after row of tiles (clipped at the edges), so that the 16 rays of a packet leave in
// neighbouring directions and Embree's packet traversal (RTC_INTERSECT_CONTEXT_FLAG_COHERENT)
// visits the same nodes for most of them: half the CPU of single incoherent rays on a city.
inline void tile_order(std::uint32_t m, std::vector<std::uint32_t>& order) {
    order.clear();
    order.reserve(static_cast<std::size_t>(m) * m);
    for (std::uint32_t ty = 0; ty < m; ty += 4)
        for (std::uint32_t tx = 0; tx < m; tx += 4)
            for (std::uint32_t y = ty; y < std::min(ty + 4, m); ++y)
                for (std::uint32_t x = tx; x < std::min(tx + 4, m); ++x) order.push_back(pack_stratum(x, y));
}

}  // namespace ffcube::raycast_sampling
