// View3D's own L-shaped-room example (examples/l_shaped_room.vs3: black surfaces, the floor and
// ceiling each combined from three parts with cmb), against references made without ffcube's
// machinery (cli/l_room_reference.hpp): closed forms for the pairs that see each other whole,
// Lambert's exact point factor to the visible part integrated over the sender for the pairs
// that the re-entrant corner partly hides.
#include <gtest/gtest.h>

#include <cstdio>
#include <sstream>
#include <string>
#include <vector>

#include "cli/cli_util.hpp"
#include "support/view3d_text.hpp"
#include "cli/l_room_reference.hpp"

namespace ffcube {
namespace {

using test::read_text;
using test::run_ffcube;
using test::TempDir;

const std::string kRoom = std::string(FFCUBE_SOURCE_DIR) + "/examples/l_shaped_room.vs3";

// Input surfaces (0-based) → output surfaces after cmb: srf-7b, srf-7c into srf-7; srf-8b, srf-8c
// into srf-8.
const std::vector<std::vector<int>> kGroups = {{0}, {1}, {2}, {3}, {4}, {5}, {6, 8, 9}, {7, 10, 11}};
const std::vector<double> kArea = {9, 3, 6, 6, 3, 9, 1, 1, 2, 2, 2, 2};

// View3D's combination rule on a 12 × 12 matrix: F to a group is the sum over its parts, F from
// it the area-weighted mean.
std::vector<std::vector<double>> combined(const std::vector<std::vector<double>>& F) {
    std::vector<std::vector<double>> out(kGroups.size(), std::vector<double>(kGroups.size(), 0.0));
    for (std::size_t g = 0; g < kGroups.size(); ++g) {
        double area = 0.0;
        for (const int i : kGroups[g]) area += kArea[static_cast<std::size_t>(i)];
        for (std::size_t h = 0; h < kGroups.size(); ++h) {
            double af = 0.0;
            for (const int i : kGroups[g])
                for (const int j : kGroups[h]) af += kArea[static_cast<std::size_t>(i)] * F[static_cast<std::size_t>(i)][static_cast<std::size_t>(j)];
            out[g][h] = af / area;
        }
    }
    return out;
}

TEST(LRoomReference, IsExactToRounding) {
    // The closed forms of the unhidden pairs against the contour integral (a different formula
    // for the same integral): they agree to rounding (1e-12 with room to spare).
    for (const test::RoomPart& p : test::l_room_parts())
        for (const test::RoomPart& q : test::l_room_parts()) {
            if (p.surface == q.surface || (p.arm == test::Arm::x && q.arm == test::Arm::y) ||
                (p.arm == test::Arm::y && q.arm == test::Arm::x))
                continue;
            EXPECT_NEAR(test::unhidden_factor(p.rect, q.rect), ff_polygon_polygon(p.rect.polygon(), q.rect.polygon()), 1e-12)
                << p.surface << " " << q.surface;
        }
    const auto F16 = test::l_room_reference(16), F32 = test::l_room_reference(32);
    for (std::size_t i = 0; i < 12; ++i) {
        double sum = 0.0;
        for (std::size_t j = 0; j < 12; ++j) {
            // Gauss–Legendre on pieces where the integrand is analytic converges geometrically:
            // 16 and 32 points per direction agree to rounding, so each is within ~1e-12.
            EXPECT_NEAR(F16[i][j], F32[i][j], 1e-12) << i << " " << j;
            // Reciprocity, A_i F_ij = A_j F_ji: each pair is computed once, from the x arm's side.
            EXPECT_NEAR(kArea[i] * F32[i][j], kArea[j] * F32[j][i], 1e-12) << i << " " << j;
            sum += F32[i][j];
        }
        // The room is closed: each row sums to 1. The hidden pairs' values come from a different
        // method than the rest of the row, so this checks them against the closed forms.
        EXPECT_NEAR(sum, 1.0, 1e-12) << "row " << i;
    }
    // The partial hiding is real: srf-1 sees srf-6 whole only within 1.5 of the corner (Pinney
    // and Bean's test; View3D's manual), so the value lies below the unhidden closed form.
    const auto parts = test::l_room_parts();
    EXPECT_LT(F32[0][5], (parts[0].rect.area() * test::unhidden_factor(parts[0].rect, parts[6].rect) +
                          parts[1].rect.area() * test::unhidden_factor(parts[1].rect, parts[7].rect) +
                          parts[0].rect.area() * test::unhidden_factor(parts[0].rect, parts[7].rect) +
                          parts[1].rect.area() * test::unhidden_factor(parts[1].rect, parts[6].rect)) /
                             9.0 -
                         1e-3);
}

// ffcube's View3D file for the room, within 2e-5 of the reference (issue 14's requirement for
// this example). The reference is exact to 1e-12 (above) and the file's %.6f adds 5e-7, so the
// bound tests ffcube's error, at the settings docs/outputs.md gives for it: patches of at most
// 0.5 (each surface meshed, so every row's sender integration has 36 or more points; the output
// is per surface as View3D's) at resolution 512. With --no-subdivide (one hemicube row per
// surface) the partly hidden pairs are off by up to 7e-3 (docs/outputs.md): a point sample of a
// 3 × 3 wall cannot follow where the corner starts to hide the other arm.
TEST(LRoomCli, View3dFileWithin2e5OfTheReference) {
    TempDir dir;
    const auto r = run_ffcube("formfactors " + kRoom + " --max-patch-edge 0.5 --resolution 512 -q --view3d " + (dir / "vf.txt"));
    ASSERT_EQ(r.code, 0) << r.output;
    const test::View3dText f = test::read_view3d(read_text(dir / "vf.txt"));
    EXPECT_EQ(f.encl, 0);
    EXPECT_EQ(f.emit, 0);
    const std::size_t n = f.n;
    ASSERT_EQ(n, kGroups.size());
    const auto ref = combined(test::l_room_reference(16));
    for (std::size_t g = 0; g < n; ++g) {
        double expected = 0.0;
        for (const int i : kGroups[g]) expected += kArea[static_cast<std::size_t>(i)];
        EXPECT_NEAR(f.area[g], expected, 1e-5) << g;
    }
    double worst = 0.0;
    for (std::size_t g = 0; g < n; ++g)
        for (std::size_t h = 0; h < n; ++h) {
            const double v = f.F[g][h];
            EXPECT_NEAR(v, ref[g][h], 2e-5) << g + 1 << " -> " << h + 1;
            worst = std::max(worst, std::abs(v - ref[g][h]));
        }
    std::printf("L-shaped room, View3D file: max |F - reference| = %.2e\n", worst);
}

}  // namespace
}  // namespace ffcube
