// View3D's own L-shaped-room example (examples/l_shaped_room.vs3: black surfaces, the floor and
// ceiling each combined from three parts with cmb), against references made without ffcube's
// machinery (ffcube/reference/l_room.hpp): closed forms for the pairs that see each other whole,
// Lambert's exact point factor to the visible part integrated over the sender for the pairs
// that the re-entrant corner partly hides.
#include <gtest/gtest.h>

#include <cstdio>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>
#include <vector>

#include "cli/cli_util.hpp"
#include "support/view3d_text.hpp"
#include "ffcube/reference/l_room.hpp"

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
    for (const l_room::RoomPart& p : l_room::l_room_parts())
        for (const l_room::RoomPart& q : l_room::l_room_parts()) {
            if (p.surface == q.surface || (p.arm == l_room::Arm::x && q.arm == l_room::Arm::y) ||
                (p.arm == l_room::Arm::y && q.arm == l_room::Arm::x))
                continue;
            EXPECT_NEAR(l_room::unhidden_factor(p.rect, q.rect), ff_polygon_polygon(p.rect.polygon(), q.rect.polygon()), 1e-12)
                << p.surface << " " << q.surface;
        }
    const auto F16 = l_room::l_room_reference(16), F32 = l_room::l_room_reference(32);
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
    const auto parts = l_room::l_room_parts();
    EXPECT_LT(F32[0][5], (parts[0].rect.area() * l_room::unhidden_factor(parts[0].rect, parts[6].rect) +
                          parts[1].rect.area() * l_room::unhidden_factor(parts[1].rect, parts[7].rect) +
                          parts[0].rect.area() * l_room::unhidden_factor(parts[0].rect, parts[7].rect) +
                          parts[1].rect.area() * l_room::unhidden_factor(parts[1].rect, parts[6].rect)) /
                             9.0 -
                         1e-3);
}

// The View3D file's largest |F − reference| into `worst` (each entry also asserted within
// `tolerance`).
void view3d_file_error(const std::string& path, double tolerance, double& worst) {
    const test::View3dText f = test::read_view3d(read_text(path));
    EXPECT_EQ(f.encl, 0);
    EXPECT_EQ(f.emit, 0);
    const std::size_t n = f.n;
    ASSERT_EQ(n, kGroups.size());
    const auto ref = combined(l_room::l_room_reference(16));
    for (std::size_t g = 0; g < n; ++g) {
        double expected = 0.0;
        for (const int i : kGroups[g]) expected += kArea[static_cast<std::size_t>(i)];
        EXPECT_NEAR(f.area[g], expected, 1e-5) << g;
    }
    worst = 0.0;
    for (std::size_t g = 0; g < n; ++g)
        for (std::size_t h = 0; h < n; ++h) {
            const double v = f.F[g][h];
            EXPECT_NEAR(v, ref[g][h], tolerance) << g + 1 << " -> " << h + 1;
            worst = std::max(worst, std::abs(v - ref[g][h]));
        }
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
    double worst = 0.0;
    view3d_file_error(dir / "vf.txt", 2e-5, worst);
    std::printf("L-shaped room, View3D file: max |F - reference| = %.2e\n", worst);
}

// One patch per surface (--no-subdivide) with exact visibility (docs/accuracy.md): every pair the
// corner partly hides has at most 8 possible occluders in its shaft (srf-3 and srf-4 among them), so it gets the
// exact factor past them instead of being refused; with the unhidden near pairs exact too, every
// row is analytic and no hemicube is drawn. Bound, derived: each partly hidden entry is within its
// adaptive rule's tolerance, 1e-6 (the estimate bounds the error: VisibleFF.LShapedRoomAgainstTheReference);
// a combined surface sums ≤ 3 parts (3e-6); closed-row rebalancing moves an entry by at most its
// row's Σ error bounds (≤ 11 partly hidden or exact entries: 1.1e-5); the file's %.6f adds 5e-7:
// 1.46e-5, within issue 14's 2e-5, asserted as that. (Without it: 6.6e-3, srf-1 -> srf-6.)
TEST(LRoomCli, NoSubdivideWithExactVisibilityWithin2e5OfTheReference) {
    TempDir dir;
    const auto r = run_ffcube("formfactors " + kRoom + " --no-subdivide --exact-visibility 8 -q --view3d " + (dir / "vf.txt") +
                              " --report " + (dir / "r.json"));
    ASSERT_EQ(r.code, 0) << r.output;
    double worst = 0.0;
    view3d_file_error(dir / "vf.txt", 2e-5, worst);
    std::printf("L-shaped room, --no-subdivide --exact-visibility 8: max |F - reference| = %.2e\n", worst);
    const auto c = nlohmann::json::parse(read_text(dir / "r.json"))["corrections"];
    EXPECT_GT(c["pairs_exact_visibility"].get<int>(), 0);
    EXPECT_EQ(c["exact_visibility_unconverged"].get<int>(), 0);
    EXPECT_EQ(c["pairs_refused_possibly_occluded"].get<int>(), 0);
    EXPECT_EQ(c["rows_analytic"].get<int>(), 12);
}

// The same at the defaults (issue 14's target: 2e-5 without options): `--exact-visibility auto`
// makes every partly hidden pair exact within the per-row budget (each of the 8 rows it tries
// would otherwise draw 4 x 4 sub-hemicubes; its pairs take at most 4 times their cost,
// exact_visibility_budget_for_hemicube), so the values are those of `--exact-visibility 8` and the
// bound derived above holds as it is.
TEST(LRoomCli, NoSubdivideAtTheDefaultsWithin2e5OfTheReference) {
    TempDir dir;
    const auto r = run_ffcube("formfactors " + kRoom + " --no-subdivide -q --view3d " + (dir / "vf.txt") +
                              " --report " + (dir / "r.json"));
    ASSERT_EQ(r.code, 0) << r.output;
    double worst = 0.0;
    view3d_file_error(dir / "vf.txt", 2e-5, worst);
    std::printf("L-shaped room, --no-subdivide at the defaults: max |F - reference| = %.2e\n", worst);
    const auto c = nlohmann::json::parse(read_text(dir / "r.json"))["corrections"];
    EXPECT_EQ(c["exact_visibility_mode"], "auto");
    EXPECT_EQ(c["pairs_exact_visibility"].get<int>(), 28);
    EXPECT_EQ(c["exact_visibility_over_budget"].get<int>(), 0);
    EXPECT_EQ(c["rows_analytic"].get<int>(), 12);
    // The same file as with the explicit K (no budget).
    const auto k = run_ffcube("formfactors " + kRoom + " --no-subdivide --exact-visibility 8 -q --view3d " + (dir / "k.txt"));
    ASSERT_EQ(k.code, 0) << k.output;
    EXPECT_EQ(read_text(dir / "vf.txt"), read_text(dir / "k.txt"));
    // Off, it is what it was: the corner's pairs measured by sub-hemicubes, off by up to 7e-3.
    const auto o = run_ffcube("formfactors " + kRoom + " --no-subdivide --exact-visibility off -q --view3d " + (dir / "o.txt"));
    ASSERT_EQ(o.code, 0) << o.output;
    double worst_off = 0.0;
    const test::View3dText f = test::read_view3d(read_text(dir / "o.txt"));
    const auto ref = combined(l_room::l_room_reference(16));
    for (std::size_t g = 0; g < f.n; ++g)
        for (std::size_t h = 0; h < f.n; ++h) worst_off = std::max(worst_off, std::abs(f.F[g][h] - ref[g][h]));
    EXPECT_GT(worst_off, 1e-3);
}

}  // namespace
}  // namespace ffcube
