// Hemicube frames: orthonormal and right-handed for every normal (including the ones that
// break naive constructions), rotated by the requested angle; the per-patch angle is a
// deterministic, well-spread hash.
#include "ffcube/core/error.hpp"
#include "ffcube/hemicube/frame.hpp"

#include <glm/geometric.hpp>
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <random>
#include <vector>

namespace ffcube {
namespace {

constexpr double kPi = std::numbers::pi;

std::vector<Vec3> test_normals() {
    std::vector<Vec3> ns = {{0, 0, 1},  {0, 0, -1},        {1, 0, 0},         {-1, 0, 0},
                            {0, 1, 0},  {0, -1, 0},        {0, 1e-9, -1},     {1e-12, 0, -1},
                            {1, 1, 1},  {-3, 0.5, -1e-7},  {1e-300, 0, 1e-300}};
    std::mt19937_64 rng(11);
    std::normal_distribution<double> g;
    for (int i = 0; i < 2000; ++i) ns.emplace_back(g(rng), g(rng), g(rng));
    return ns;
}

TEST(HemicubeFrame, OrthonormalAndRightHanded) {
    // Duff et al.'s construction is accurate to a few ulps for every unit normal: 1e-12 leaves
    // room for the normalisation of the input and the rotation.
    for (const Vec3& raw : test_normals())
        for (double angle : {0.0, 0.3, 2.0, 5.9}) {
            const HemicubeFrame f = make_frame(raw, angle);
            EXPECT_NEAR(glm::length(f.tangent), 1.0, 1e-12);
            EXPECT_NEAR(glm::length(f.bitangent), 1.0, 1e-12);
            EXPECT_NEAR(glm::length(f.normal), 1.0, 1e-12);
            EXPECT_NEAR(glm::dot(f.tangent, f.bitangent), 0.0, 1e-12);
            EXPECT_NEAR(glm::dot(f.tangent, f.normal), 0.0, 1e-12);
            EXPECT_NEAR(glm::dot(f.bitangent, f.normal), 0.0, 1e-12);
            EXPECT_NEAR(glm::length(glm::cross(f.tangent, f.bitangent) - f.normal), 0.0, 1e-12);
            // The normal is the input's direction (scaled first: |(1e-300, 0, 1e-300)|² underflows).
            const Vec3 m = raw / std::max({std::abs(raw.x), std::abs(raw.y), std::abs(raw.z)});
            EXPECT_NEAR(glm::length(f.normal - m / glm::length(m)), 0.0, 1e-12);
        }
}

TEST(HemicubeFrame, RotatesAboutTheNormal) {
    const Vec3 n(0.2, -0.7, 0.4);
    const HemicubeFrame f0 = make_frame(n, 0.0);
    for (double angle : {0.25, 1.0, 3.0, -2.0}) {
        const HemicubeFrame f = make_frame(n, angle);
        // Counter-clockwise seen from the normal's tip: t(φ) = cos φ t0 + sin φ b0.
        EXPECT_NEAR(glm::dot(f.tangent, f0.tangent), std::cos(angle), 1e-14);
        EXPECT_NEAR(glm::dot(f.tangent, f0.bitangent), std::sin(angle), 1e-14);
        EXPECT_NEAR(glm::length(f.normal - f0.normal), 0.0, 1e-15);
    }
    // to_local inverts to_world.
    const HemicubeFrame f = make_frame(n, 1.3);
    const Vec3 v(0.3, -2.0, 5.0);
    EXPECT_NEAR(glm::length(f.to_local(f.to_world(v)) - v), 0.0, 1e-14);
    EXPECT_NEAR(f.to_local(f.normal).z, 1.0, 1e-15);
}

TEST(HemicubeFrame, RejectsDegenerateNormals) {
    EXPECT_THROW(make_frame(Vec3(0.0), 0.0), InternalError);
    EXPECT_THROW(make_frame(Vec3(std::nan(""), 0, 1), 0.0), InternalError);
}

TEST(HemicubeAngle, SplitMixReferenceValue) {
    // First output of the reference splitmix64 generator (Vigna) from state 0.
    EXPECT_EQ(splitmix64(0), 0xe220a8397b1dcdafULL);
}

TEST(HemicubeAngle, DeterministicInRangeAndSpread) {
    EXPECT_EQ(hemicube_angle(42, 7), hemicube_angle(42, 7));
    EXPECT_NE(hemicube_angle(42, 7), hemicube_angle(43, 7));
    EXPECT_NE(hemicube_angle(42, 7), hemicube_angle(42, 8));
    // Symmetric about π (each quadrant's range is symmetric about its middle), spread over
    // [0, 2π) about as a uniform angle: the mean of n has standard deviation ≈ (2π/√12)/√n; 5σ.
    const int n = 100000;
    double sum = 0.0;
    for (std::uint32_t p = 0; p < static_cast<std::uint32_t>(n); ++p) {
        const double a = hemicube_angle(1, p);
        ASSERT_GE(a, 0.0);
        ASSERT_LT(a, 2.0 * kPi);
        // Never within 5° of a multiple of 90° (rounding of the quadrant arithmetic: 1e-15).
        const double q = std::fmod(a, kPi / 2);
        ASSERT_GE(q, kPi / 36 - 1e-12) << a;
        ASSERT_LE(q, kPi / 2 - kPi / 36 + 1e-12) << a;
        sum += a;
    }
    const double sigma = 2.0 * kPi / std::sqrt(12.0) / std::sqrt(static_cast<double>(n));
    EXPECT_NEAR(sum / n, kPi, 5.0 * sigma);
}

}  // namespace
}  // namespace ffcube
