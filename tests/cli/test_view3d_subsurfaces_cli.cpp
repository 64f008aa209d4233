// View3D subsurfaces, null and masking surfaces through the real binary: a 2 × 2 wall with a
// 1 × 1 square (a window, a hole or a mask) in its middle, facing a parallel 2 × 2 wall at
// distance 1; expected factors from view-factor algebra on Howell's C-11 and C-12.
#include <gtest/gtest.h>

#include <fstream>
#include <map>
#include <sstream>
#include <string>
#include <vector>

#include "cli/cli_util.hpp"
#include "support/view3d_text.hpp"
#include "ffcube/reference/closed_forms.hpp"
#include "ffcube/geometry/analytic.hpp"

namespace ffcube {
namespace {

using test::read_text;
using test::run_ffcube;
using test::TempDir;

// The wall and window (vertices 1–8), and the opposite wall 1 above (9–12).
const std::string kVertices = std::string(test::kVs3WindowWallVertices) + R"(V 9 0 0 1
V 10 2 0 1
V 11 2 2 1
V 12 0 2 1
)";

// Closed forms: the window (x, y ∈ [0.5, 1.5]) to the opposite wall ([0, 2]², 1 above): C-12; the
// whole wall to it: C-11; the wall less the window: (A_W F_W − A_w F_w)/(A_W − A_w).
const double kWindowToWall = ff_parallel_rectangles_offset(0.5, 1.5, 0.5, 1.5, 0.0, 2.0, 0.0, 2.0, 1.0);
const double kWholeToWall = ff_parallel_rectangles(2.0, 2.0, 1.0);
const double kRestToWall = (4.0 * kWholeToWall - 1.0 * kWindowToWall) / 3.0;

// Every pair here is near and unoccluded (parallel plates), so ffcube's values are the exact
// polygon-to-polygon ones, stored as float (2^-24 relative) and written as %.6f (5e-7): 1e-6.
constexpr double kTol = 1e-6;

// The matrix's size line (the first line after the % comments): its row count.
std::size_t mtx_rows(const std::string& text) {
    std::istringstream in(text);
    std::string line;
    while (std::getline(in, line) && line[0] == '%') {
    }
    return std::stoul(line);
}

// One square (vertices 5–8) on the wall, as each kind of View3D surface:
// - S, a subsurface (a window): View3D subtracts the window's factors from the wall's and its
//   area from the wall's area, which makes the wall's factors those of the wall less the window.
// - N, a null surface: it takes the square out of the wall (area and factors, as View3D's DelNull
//   does) and has no row or column; what would have seen the square is blocked and counted
//   nowhere, so the opposite wall's sky view factor is 1 − F(opposite → whole wall).
// - M, a masking surface facing the wall: View3D keeps it as a surface that sees only its base
//   (F(mask → wall) = 1, F(wall → mask) = A_mask / A_wall) and keeps the wall's area whole; the
//   masked part of the wall sees nothing else, so F(wall → opposite) = A_rest F_rest / A_wall.
// In all three the opposite wall sees the whole 2 × 2 wall's area (window, hole or the mask's
// back, which blocks) and nothing else: sky = 1 − C-11.
struct Entry {
    std::size_t i, j;
    double value;
};
struct SurfaceCase {
    const char* name;
    const char* square;  // the square's line
    std::vector<double> area;
    std::vector<Entry> F;
};
const std::vector<SurfaceCase> kCases = {
    {"window", "S 2 5 6 7 8 1 0 0.9 window", {3.0, 1.0, 4.0},
     // F(window → wall), F(wall − window → wall), reciprocity; coplanar: the window and the rest
     // of its wall do not see each other.
     {{1, 2, kWindowToWall}, {0, 2, kRestToWall}, {2, 1, kWindowToWall / 4.0}, {2, 0, 3.0 * kRestToWall / 4.0}, {0, 1, 0.0}, {1, 0, 0.0}}},
    {"null", "N 2 8 7 6 5 1 0 0.9 hole", {3.0, 4.0}, {{0, 1, kRestToWall}, {1, 0, 3.0 * kRestToWall / 4.0}}},
    {"mask", "M 2 8 7 6 5 1 0 0.5 mask", {4.0, 1.0, 4.0},
     // The opposite wall sees the mask's back: blocked, counted nowhere.
     {{0, 1, 0.25}, {0, 2, 3.0 * kRestToWall / 4.0}, {1, 0, 1.0}, {1, 2, 0.0}, {2, 1, 0.0}, {2, 0, 3.0 * kRestToWall / 4.0}}},
};

TEST(View3dSubsurfaceCli, WindowNullAndMaskOverASquareOfTheWall) {
    std::map<std::string, std::size_t> matrix_rows;
    for (const SurfaceCase& c : kCases) {
        SCOPED_TRACE(c.name);
        TempDir dir;
        test::write_file(dir / "w.vs3", std::string("T ") + c.name + "\n" + kVertices + "S 1 1 2 3 4 0 0 0.9 wall\n" + c.square +
                                            "\nS 3 9 12 11 10 0 0 0.9 opposite\nEnd\n");
        const auto r = run_ffcube("formfactors " + (dir / "w.vs3") + " --no-subdivide -q --view3d " + (dir / "vf.txt") + " -o " +
                                  (dir / "F.mtx") + " --sky " + (dir / "sky.csv") + " --sky-by object");
        ASSERT_EQ(r.code, 0) << r.output;
        const test::View3dText f = test::read_view3d(read_text(dir / "vf.txt"));
        ASSERT_EQ(f.n, c.area.size());
        for (std::size_t i = 0; i < f.n; ++i) EXPECT_NEAR(f.area[i], c.area[i], 1e-6) << i;
        for (const Entry& e : c.F) EXPECT_NEAR(f.F[e.i][e.j], e.value, kTol) << e.i << " -> " << e.j;
        // The CSV's 9 digits and float rows: 1e-6.
        EXPECT_NEAR(test::last_column_by_first(read_text(dir / "sky.csv")).at("opposite"), 1.0 - kWholeToWall, kTol);
        matrix_rows[c.name] = mtx_rows(read_text(dir / "F.mtx"));
    }
    // The matrix (.mtx) has the radiating surfaces only: the wall's pieces (the same cut for all
    // three), the window's row, and the opposite wall; the null surface and the mask have none.
    EXPECT_EQ(matrix_rows["window"], matrix_rows["null"] + 1);
    EXPECT_EQ(matrix_rows["mask"], matrix_rows["null"]);
}

TEST(View3dSubsurfaceCli, SubsurfaceOffItsBaseIsRefusedNamingTheLine) {
    TempDir dir;
    test::write_file(dir / "bad.vs3", "T bad\n" + kVertices + R"(S 1 1 2 3 4 0 0 0.9 wall
S 2 9 10 11 12 1 0 0.9 window
End
)");
    const auto r = run_ffcube("formfactors " + (dir / "bad.vs3") + " --no-subdivide -q --view3d " + (dir / "vf.txt"));
    EXPECT_EQ(r.code, 2) << r.output;
    EXPECT_NE(r.output.find("bad.vs3:16: subsurface 2 cannot lie on its base surface 1 (line 15): a vertex (0, 0, 1) is 1 off "
                            "the base's plane"),
              std::string::npos)
        << r.output;
    EXPECT_FALSE(std::filesystem::exists(dir / "vf.txt"));
}

}  // namespace
}  // namespace ffcube
