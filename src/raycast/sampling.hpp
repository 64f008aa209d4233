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

// Cosine-weighted direction about nrm from (r1, r2) uniform on the unit square, through the
// concentric map of the square onto the disk (Shirley and Chiu 1997), which keeps strata compact
// (the polar map would make wedges thin near the pole), lifted to the hemisphere (Malley).
// φ = π/4 · b/a, or π/2 − π/4 · a/b (cos and sin swap): a quarter turn at most either way.
inline Vec3 cosine_direction(double r1, double r2, const Vec3& tu, const Vec3& tv, const Vec3& nrm) {
    const double a = 2.0 * r1 - 1.0, b = 2.0 * r2 - 1.0;
    double x = 0.0, y = 0.0;
    if (a * a > b * b) {
        double s = 0.0, c = 0.0;
        sincos_quarter_turn(b / a, s, c);
        x = a * c, y = a * s;
    } else if (b != 0.0) {
        double s = 0.0, c = 0.0;
        sincos_quarter_turn(a / b, s, c);
        x = b * s, y = b * c;
    }
    return x * tu + y * tv + std::sqrt(std::max(0.0, 1.0 - x * x - y * y)) * nrm;
}

// The direction strata of an m × m batch in the order its rays are cast: 4 × 4 tiles of the
// square, row after row of tiles (clipped at the edges), so that the 16 rays of a packet leave in
// neighbouring directions and Embree's packet traversal (RTC_INTERSECT_CONTEXT_FLAG_COHERENT)
// visits the same nodes for most of them: half the CPU of single incoherent rays on a city.
inline void tile_order(std::uint32_t m, std::vector<std::uint32_t>& order) {
    order.clear();
    order.reserve(static_cast<std::size_t>(m) * m);
    for (std::uint32_t ty = 0; ty < m; ty += 4)
        for (std::uint32_t tx = 0; tx < m; tx += 4)
            for (std::uint32_t y = ty; y < std::min(ty + 4, m); ++y)
                for (std::uint32_t x = tx; x < std::min(tx + 4, m); ++x) order.push_back(y * m + x);
}

}  // namespace ffcube::raycast_sampling
