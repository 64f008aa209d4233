// View3D subsurfaces and null surfaces through the real binary: a 2 × 2 wall with a 1 × 1 window
// (a subsurface) in its middle, facing a parallel 2 × 2 wall at distance 1. View3D subtracts the
// window's factors from the wall's and its area from the wall's area, which makes the wall's
// factors those of the wall less the window: view-factor algebra on Howell's C-11 and C-12.
#include <gtest/gtest.h>

#include <fstream>
#include <map>
#include <sstream>
#include <string>
#include <vector>

#include "cli/cli_util.hpp"
#include "ffcube/geometry/analytic.hpp"

namespace ffcube {
namespace {

using test::read_text;
using test::run_ffcube;
using test::TempDir;

const char* kVertices = R"(F 3
V 1 0 0 0
V 2 2 0 0
V 3 2 2 0
V 4 0 2 0
V 5 0.5 0.5 0
V 6 1.5 0.5 0
V 7 1.5 1.5 0
V 8 0.5 1.5 0
V 9 0 0 1
V 10 2 0 1
V 11 2 2 1
V 12 0 2 1
)";

struct View3dFile {
    std::size_t n = 0;
    std::vector<double> area;
    std::vector<std::vector<double>> F;
};
View3dFile read_view3d(const std::string& bytes) {
    View3dFile f;
    std::istringstream in(bytes);
    std::string program, version;
    int format, encl, emit;
    in >> program >> version >> format >> encl >> emit >> f.n;
    f.area.resize(f.n);
    f.F.assign(f.n, std::vector<double>(f.n));
    for (auto& a : f.area) in >> a;
    for (auto& row : f.F)
        for (auto& v : row) in >> v;
    EXPECT_TRUE(in);
    return f;
}

// Closed forms: the window (x, y ∈ [0.5, 1.5]) to the opposite wall ([0, 2]², 1 above): C-12; the
// whole wall to it: C-11; the wall less the window: (A_W F_W − A_w F_w)/(A_W − A_w).
const double kWindowToWall = ff_parallel_rectangles_offset(0.5, 1.5, 0.5, 1.5, 0.0, 2.0, 0.0, 2.0, 1.0);
const double kWholeToWall = ff_parallel_rectangles(2.0, 2.0, 1.0);
const double kRestToWall = (4.0 * kWholeToWall - 1.0 * kWindowToWall) / 3.0;

// Every pair here is near and unoccluded (parallel plates), so ffcube's values are the exact
// polygon-to-polygon ones, stored as float (2^-24 relative) and written as %.6f (5e-7): 1e-6.
constexpr double kTol = 1e-6;

TEST(View3dSubsurfaceCli, WindowInAWallFacingAParallelWall) {
    TempDir dir;
    std::ofstream(dir / "w.vs3") << "T window\n" << kVertices << R"(S 1 1 2 3 4 0 0 0.9 wall
S 2 5 6 7 8 1 0 0.9 window
S 3 9 12 11 10 0 0 0.9 opposite
End
)";
    const auto r = run_ffcube("formfactors " + (dir / "w.vs3") + " --no-subdivide -q --view3d " + (dir / "vf.txt"));
    ASSERT_EQ(r.code, 0) << r.output;
    const View3dFile f = read_view3d(read_text(dir / "vf.txt"));
    ASSERT_EQ(f.n, 3u);
    EXPECT_NEAR(f.area[0], 3.0, 1e-6);  // the wall's area less the window's, as View3D reports it
    EXPECT_NEAR(f.area[1], 1.0, 1e-6);
    EXPECT_NEAR(f.F[1][2], kWindowToWall, kTol);                    // F(window → wall)
    EXPECT_NEAR(f.F[0][2], kRestToWall, kTol);                      // F(wall − window → wall)
    EXPECT_NEAR(f.F[2][1], 1.0 * kWindowToWall / 4.0, kTol);        // reciprocity
    EXPECT_NEAR(f.F[2][0], 3.0 * kRestToWall / 4.0, kTol);
    EXPECT_EQ(f.F[0][1], 0.0);  // coplanar: the window and the rest of its wall do not see each other
    EXPECT_EQ(f.F[1][0], 0.0);
}

// A null surface over the same square: it takes the square out of the wall (area and factors, as
// View3D's DelNull does) and has no row or column; what would have seen the square is blocked
// and counted nowhere, so the opposite wall's sky view factor is 1 − F(opposite → whole wall).
TEST(View3dSubsurfaceCli, NullSurfaceRemovesTheCoveredPart) {
    TempDir dir;
    std::ofstream(dir / "n.vs3") << "T null\n" << kVertices << R"(S 1 1 2 3 4 0 0 0.9 wall
N 2 8 7 6 5 1 0 0.9 hole
S 3 9 12 11 10 0 0 0.9 opposite
End
)";
    const auto r = run_ffcube("formfactors " + (dir / "n.vs3") + " --no-subdivide -q --view3d " + (dir / "vf.txt") + " --sky " +
                              (dir / "sky.csv") + " --sky-by object");
    ASSERT_EQ(r.code, 0) << r.output;
    const View3dFile f = read_view3d(read_text(dir / "vf.txt"));
    ASSERT_EQ(f.n, 2u);
    EXPECT_NEAR(f.area[0], 3.0, 1e-6);
    EXPECT_NEAR(f.area[1], 4.0, 1e-6);
    EXPECT_NEAR(f.F[0][1], kRestToWall, kTol);
    EXPECT_NEAR(f.F[1][0], 3.0 * kRestToWall / 4.0, kTol);
    std::map<std::string, double> sky;
    std::istringstream in(read_text(dir / "sky.csv"));
    std::string line;
    std::getline(in, line);
    while (std::getline(in, line)) sky[line.substr(0, line.find(','))] = std::stod(line.substr(line.rfind(',') + 1));
    ASSERT_EQ(sky.size(), 2u);
    // The CSV's 9 digits and float rows: 1e-6.
    EXPECT_NEAR(sky["opposite"], 1.0 - kWholeToWall, kTol);
}

// A masking surface over the same square, facing the wall: View3D keeps it as a surface that sees
// only its base (F(mask → wall) = 1, F(wall → mask) = A_mask / A_wall) and keeps the wall's area
// whole; the masked part of the wall sees nothing else, so F(wall → opposite) = A_rest F_rest / A_wall.
TEST(View3dSubsurfaceCli, MaskingSurfaceHidesTheCoveredPartFromAllButItself) {
    TempDir dir;
    std::ofstream(dir / "m.vs3") << "T mask\n" << kVertices << R"(S 1 1 2 3 4 0 0 0.9 wall
M 2 8 7 6 5 1 0 0.5 mask
S 3 9 12 11 10 0 0 0.9 opposite
End
)";
    const auto r = run_ffcube("formfactors " + (dir / "m.vs3") + " --no-subdivide -q --view3d " + (dir / "vf.txt") + " -o " +
                              (dir / "F.mtx"));
    ASSERT_EQ(r.code, 0) << r.output;
    const View3dFile f = read_view3d(read_text(dir / "vf.txt"));
    ASSERT_EQ(f.n, 3u);  // wall, mask, opposite: the mask in its place among the surfaces
    EXPECT_NEAR(f.area[0], 4.0, 1e-6);
    EXPECT_NEAR(f.area[1], 1.0, 1e-6);
    EXPECT_NEAR(f.area[2], 4.0, 1e-6);
    EXPECT_NEAR(f.F[0][1], 0.25, kTol);
    EXPECT_NEAR(f.F[0][2], 3.0 * kRestToWall / 4.0, kTol);
    EXPECT_EQ(f.F[1][0], 1.0);
    EXPECT_EQ(f.F[1][2], 0.0);
    EXPECT_EQ(f.F[2][1], 0.0);  // the opposite wall sees the mask's back: blocked, counted nowhere
    EXPECT_NEAR(f.F[2][0], 3.0 * kRestToWall / 4.0, kTol);
    // The matrix (.mtx) has the radiating surfaces only: the wall's pieces and the opposite wall.
    EXPECT_EQ(read_text(dir / "F.mtx").find("\n6 "), std::string::npos);
}

TEST(View3dSubsurfaceCli, SubsurfaceOffItsBaseIsRefusedNamingTheLine) {
    TempDir dir;
    std::ofstream(dir / "bad.vs3") << "T bad\n" << kVertices << R"(S 1 1 2 3 4 0 0 0.9 wall
S 2 9 10 11 12 1 0 0.9 window
End
)";
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
