#include "ffcube/hemicube/frame.hpp"

#include "ffcube/core/error.hpp"

#include <glm/geometric.hpp>

#include <algorithm>
#include <cmath>
#include <numbers>

namespace ffcube {

Vec3 HemicubeFrame::to_local(const Vec3& w) const {
    return {glm::dot(w, tangent), glm::dot(w, bitangent), glm::dot(w, normal)};
}

HemicubeFrame make_frame(const Vec3& normal, double angle) {
    // Divide by the largest component first: tiny (1e-300) or huge normals then neither
    // underflow nor overflow in the length.
    const double big = std::max({std::abs(normal.x), std::abs(normal.y), std::abs(normal.z)});
    FFCUBE_CHECK_MSG(std::isfinite(big) && big > 0.0, "hemicube normal must be non-zero and finite");
    const Vec3 m = normal / big;
    const Vec3 n = m / glm::length(m);
    Vec3 b1, b2;
    orthonormal_basis(n, b1, b2);
    const double c = std::cos(angle), s = std::sin(angle);
    // Rotating both tangents by the same angle in their plane keeps b1 × b2 = n.
    return {c * b1 + s * b2, c * b2 - s * b1, n};
}

std::uint64_t splitmix64(std::uint64_t x) {
    x += 0x9e3779b97f4a7c15ULL;
    x = (x ^ (x >> 30)) * 0xbf58476d1ce4e5b9ULL;
    x = (x ^ (x >> 27)) * 0x94d049bb133111ebULL;
    return x ^ (x >> 31);
}

double hemicube_angle(std::uint64_t seed, std::uint32_t patch) {
    // Two rounds so that neighbouring seeds and neighbouring patches decorrelate.
    const std::uint64_t h = splitmix64(splitmix64(seed) ^ patch);
    // Top 53 bits → [0,1) exactly. A quadrant from it, then an angle within the quadrant that
    // keeps 5° from its ends: the hemicube's faces repeat every 90°, and at a multiple of 90°
    // the pixel grid of an axis-aligned patch lines up with the edges of axis-aligned receivers,
    // so the pixel errors along an edge add up instead of cancelling (7.6% on single patches of a
    // test scene at 180.09°; tests/gl/test_piece_kinds.cpp). Range [5°, 355°), within [0, 2π).
    const double unit = static_cast<double>(h >> 11) * 0x1.0p-53;
    const double quarter = std::floor(4.0 * unit);
    const double within = 4.0 * unit - quarter;  // [0, 1)
    const double margin = std::numbers::pi / 36.0;
    return quarter * (std::numbers::pi / 2) + margin + within * (std::numbers::pi / 2 - 2 * margin);
}

}  // namespace ffcube
