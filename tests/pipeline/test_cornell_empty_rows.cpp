// The built-in Cornell box has rows that sum to 0 (docs/solve.md): which patches, and why. Its
// blocks have no bottom face (the measured data has none), so a floor patch under a block sees
// only the inside of the block, the backs of its outward-facing sides and top; and the light
// hangs 0.1 mm below the ceiling facing down, so a ceiling patch above it sees the light's back.
// Back faces block and receive nothing, so those rows are empty: correct, not a bug. Asserted
// both ways, for the plain hemicube rows and for the rows at default settings (the near-field
// correction, which must not give such a row entries either: no pair there faces each other).
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <string>
#include <vector>

#include "ffcube/formfactor/row_provider.hpp"
#include "ffcube/io/report.hpp"
#include "ffcube/pipeline/row_source.hpp"
#include "ffcube/pipeline/scene_loading.hpp"

namespace ffcube {
namespace {

using Xz = std::array<double, 2>;

// Signed distance (mm) from p to the outside of the convex polygon 'poly' (x, z; either
// orientation): > 0 inside, by that much from the nearest edge.
double inside_by(const std::vector<Xz>& poly, const Xz& p) {
    double area2 = 0;
    for (std::size_t k = 0; k < poly.size(); ++k) {
        const Xz& a = poly[k];
        const Xz& b = poly[(k + 1) % poly.size()];
        area2 += a[0] * b[1] - b[0] * a[1];
    }
    const double side = area2 > 0 ? 1.0 : -1.0;
    double d = 1e300;
    for (std::size_t k = 0; k < poly.size(); ++k) {
        const Xz& a = poly[k];
        const Xz& b = poly[(k + 1) % poly.size()];
        const double ex = b[0] - a[0], ez = b[1] - a[1];
        const double cross = ex * (p[1] - a[1]) - ez * (p[0] - a[0]);
        d = std::min(d, side * cross / std::hypot(ex, ez));
    }
    return d;
}

// Footprints (x, z) from src/scene/builtin.cpp: the blocks' tops and the light.
const std::vector<Xz> kShortBlock{{130, 65}, {82, 225}, {240, 272}, {290, 114}};
const std::vector<Xz> kTallBlock{{423, 247}, {265, 296}, {314, 456}, {472, 406}};
const std::vector<Xz> kLight{{343, 227}, {343, 332}, {213, 332}, {213, 227}};

// Resolution of the hemicubes: small, the rows' emptiness does not depend on it beyond the
// ceiling margin below.
constexpr int kN = 64;
// A ceiling patch's rays escape through the 0.1 mm gap between ceiling and light only at
// elevations below atan(0.1 mm / d), d the horizontal way to the light's edge; the lowest
// pixel centres of the side faces lie at elevation atan(1/N) (a side face spans z ∈ [0, 1] in
// N/2 rows). So a ceiling patch whose centre lies more than 0.1 mm × N inside the light's
// footprint sees nothing but the light's back (the eye's offset above the patch, 1e-5 of its
// size, only narrows the gap).
constexpr double kCeilingMargin = 0.1 * kN;

// 'whole': where the rows are the patch's (the correction's exact area-to-area values: a floor
// patch that reaches out from under a block does see the block's sides from its outer part), a
// row must be empty when all the patch lies in the footprint; else (plain hemicube rows, measured
// from the centre) when its centre does.
double inside_by(const Scene& scene, std::uint32_t i, const std::vector<Xz>& poly, bool whole) {
    const Patch& p = scene.patches[i];
    if (!whole) return inside_by(poly, {p.centroid.x, p.centroid.z});
    double d = 1e300;
    const auto v = scene.patch_vertices(i);
    for (std::uint32_t k = 0; k < p.count; ++k) d = std::min(d, inside_by(poly, {v[k].x, v[k].z}));
    return d;
}

void check_rows(const Scene& scene, RowProvider& rows, bool whole, const std::string& what) {
    SCOPED_TRACE(what);
    const CsrMatrix F = compute_all_rows(rows);
    std::size_t empty_floor = 0, empty_ceiling = 0;
    for (std::uint32_t i = 0; i < scene.size(); ++i) {
        const Patch& p = scene.patches[i];
        const std::string& object = scene.objects[p.object];
        const Xz c{p.centroid.x, p.centroid.z};
        const double sum = F.row(i).sum();
        const bool under_block = object == "floor" && (inside_by(kShortBlock, c) > 0 || inside_by(kTallBlock, c) > 0);
        const bool above_light = object == "ceiling" && inside_by(kLight, c) > 0;
        if (sum == 0.0) {
            // Only patches (their centres) that the back faces of a block or of the light close off.
            EXPECT_TRUE(under_block || above_light) << "row " << i << " (" << object << ") is empty";
            empty_floor += under_block;
            empty_ceiling += above_light;
        }
        // Enclosed by a block (floor, four sides and top, every one seen from behind).
        if (object == "floor" && std::max(inside_by(scene, i, kShortBlock, whole), inside_by(scene, i, kTallBlock, whole)) > 0) {
            EXPECT_EQ(sum, 0.0) << "floor patch " << i << " under a block";
        }
        if (object == "ceiling" && inside_by(scene, i, kLight, whole) > kCeilingMargin) {
            EXPECT_EQ(sum, 0.0) << "ceiling patch " << i << " above the light";
        }
        // Everything else sees part of the open box's inside: a row well above 0 (the open front
        // lets at most the half-space in front of a patch escape, never all of it).
        if (!under_block && !above_light) { EXPECT_GT(sum, 0.05) << "row " << i << " (" << object << ")"; }
    }
    EXPECT_GT(empty_floor, 0u);
    EXPECT_GT(empty_ceiling, 0u);
}

TEST(CornellBox, EmptyRowsAreExactlyTheFloorUnderTheBlocksAndTheCeilingBehindTheLight) {
    SceneOptions so;  // the built-in Cornell box
    so.patches = 600;
    Report report;
    const Scene scene = load_and_mesh(so, report);
    RowOptions plain;
    plain.resolution = kN;
    plain.correct = Correction::None;
    RowSource none = make_row_source(scene, plain);
    check_rows(scene, none.provider(), false, "--correct none");
    RowOptions defaults;
    defaults.resolution = kN;
    RowSource corrected = make_row_source(scene, defaults);
    check_rows(scene, corrected.provider(), true, "default settings");
}

}  // namespace
}  // namespace ffcube
