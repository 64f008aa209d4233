// face_outcode (four comparisons at a time) against the comparisons written one by one.
#include <gtest/gtest.h>

#include <array>
#include <random>

#include "ffcube/hemicube/outcode.hpp"

namespace ffcube {
namespace {

// Points on and off every plane: coordinates drawn from a few values (so x = ±y, x = ±z, y = ±z
// and ±0 occur often) and from a continuous range.
TEST(Outcode, FourAtATimeMatchesOneByOne) {
    const std::array<float, 9> few = {0.0f, -0.0f, 1.0f, -1.0f, 2.0f, -2.0f, 1e-30f, -1e-30f, 3.5e30f};
    for (float x : few)
        for (float y : few)
            for (float z : few) ASSERT_EQ(face_outcode(x, y, z), face_outcode_scalar(x, y, z)) << x << " " << y << " " << z;
    std::mt19937 rng(5);
    std::uniform_real_distribution<float> u(-2.0f, 2.0f);
    std::uniform_int_distribution<int> pick(0, 8);
    unsigned seen = 0;
    for (int k = 0; k < 200000; ++k) {
        const float x = u(rng), y = k % 3 == 0 ? few[static_cast<std::size_t>(pick(rng))] : u(rng);
        const float z = k % 5 == 0 ? (k % 2 ? x : -y) : u(rng);
        const unsigned c = face_outcode_scalar(x, y, z);
        ASSERT_EQ(face_outcode(x, y, z), c) << x << " " << y << " " << z;
        seen |= c;
    }
    EXPECT_EQ(seen, (1u << 13) - 1) << "every bit set by some point";
}

}  // namespace
}  // namespace ffcube
