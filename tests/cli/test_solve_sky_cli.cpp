// `ffcube solve --sky` (issue 14): the sky view factors of the scene solved, in the same file and
// under the same report keys as `ffcube formfactors --sky` (docs/outputs.md). Checked against the
// closed form of two opposed squares, against formfactors' file byte for byte (rows computed by
// the solve's own provider, from a .ffm, and with obstruction-only surfaces), and the refusals.
#include <gtest/gtest.h>

#include <fstream>
#include <map>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>

#include "cli/cli_util.hpp"
#include "ffcube/reference/closed_forms.hpp"
#include "ffcube/geometry/analytic.hpp"

namespace ffcube {
namespace {

using test::example;
using test::read_text;
using test::run_ffcube;
using test::last_column_by_first;
using test::TempDir;
using test::write_file;

// examples/parallel_squares.obj with square a emitting: the solve has something to shoot.
std::string emitting_squares(const TempDir& dir) {
    write_file(dir / "m.csv", "object,kd_r,kd_g,kd_b,ke_r,ke_g,ke_b\na,0.5,0.5,0.5,1,1,1\nb,0.5,0.5,0.5,0,0,0\n");
    return example("parallel_squares.obj") + " --materials " + (dir / "m.csv");
}

TEST(SolveSky, OpposedSquaresGiveOneMinusTheClosedForm) {
    TempDir dir;
    const auto r = run_ffcube("solve " + emitting_squares(dir) + " --no-subdivide -q --sky " + (dir / "sky.csv") +
                              " --sky-by object --report " + (dir / "r.json"));
    ASSERT_EQ(r.code, 0) << r.output;
    // Each square sees only the other: SVF = 1 − F(a→b), F from Howell's C-11 (0.1998244).
    const double exact = 1.0 - ff_parallel_rectangles(1.0, 1.0, 1.0);
    const auto sky = last_column_by_first(read_text(dir / "sky.csv"));
    ASSERT_EQ(sky.size(), 2u);
    // The pair is near (centroids 1 apart, within 3 patch sizes) and unoccluded, so the default
    // correction gives the exact area-to-area value; what is left is the float32 entry (2^-24
    // relative) and the CSV's 9 digits: 1e-6 covers both with room.
    EXPECT_NEAR(sky.at("a"), exact, 1e-6);
    EXPECT_NEAR(sky.at("b"), exact, 1e-6);
    const auto report = nlohmann::json::parse(read_text(dir / "r.json"));
    EXPECT_NEAR(report["sky"]["min"].get<double>(), exact, 1e-6);
    EXPECT_NEAR(report["sky"]["max"].get<double>(), exact, 1e-6);
    EXPECT_NEAR(report["sky"]["area_weighted_mean"].get<double>(), exact, 1e-6);
    // Without --sky the solve computes only the shooters' rows and reports no sky.
    const auto plain = run_ffcube("solve " + emitting_squares(dir) + " --no-subdivide -q --report " + (dir / "p.json"));
    ASSERT_EQ(plain.code, 0) << plain.output;
    EXPECT_FALSE(nlohmann::json::parse(read_text(dir / "p.json")).contains("sky"));
}

TEST(SolveSky, SameFileAsFormfactorsForTheSameOptions) {
    TempDir dir;
    // Meshed (32 patches; hemicube rows, partly measured), per patch: the solve's provider computes
    // every row, as formfactors does, so the files are the same bytes.
    const std::string common = emitting_squares(dir) + " --max-patch-edge 0.25 --resolution 64 -q --sky ";
    auto r = run_ffcube("solve " + common + (dir / "solve.csv") + " --report " + (dir / "r.json"));
    ASSERT_EQ(r.code, 0) << r.output;
    r = run_ffcube("formfactors " + common + (dir / "ff.csv") + " -o " + (dir / "F.ffm"));
    ASSERT_EQ(r.code, 0) << r.output;
    const std::string ff = read_text(dir / "ff.csv");
    EXPECT_EQ(last_column_by_first(ff).size(), 32u);
    EXPECT_EQ(read_text(dir / "solve.csv"), ff);
    // The rows the solve shot kept their sums (those bytes above included them): exactly the
    // patches that got a row in the solve; only the others were computed for the sky.
    const auto report = nlohmann::json::parse(read_text(dir / "r.json"));
    const auto without_row = report["row_cache"]["patches_without_row"].get<double>();
    EXPECT_EQ(report["sky"]["rows_reused"].get<double>(), 32.0 - without_row);
    EXPECT_EQ(report["sky"]["rows_computed"].get<double>(), without_row);
    EXPECT_GT(report["sky"]["rows_reused"].get<double>(), 0.0);
    // Square b black (ρ = 0, no emission): its 16 patches never hold unshot energy, so the solve
    // never asks for their rows, and the sky computes those 16 alone; the bytes stay the same.
    write_file(dir / "black.csv", "object,kd_r,kd_g,kd_b,ke_r,ke_g,ke_b\na,0.5,0.5,0.5,1,1,1\nb,0,0,0,0,0,0\n");
    r = run_ffcube("solve " + example("parallel_squares.obj") + " --materials " + (dir / "black.csv") +
                   " --max-patch-edge 0.25 --resolution 64 -q --sky " + (dir / "black_sky.csv") + " --report " + (dir / "b.json"));
    ASSERT_EQ(r.code, 0) << r.output;
    EXPECT_EQ(read_text(dir / "black_sky.csv"), ff);
    const auto black = nlohmann::json::parse(read_text(dir / "b.json"));
    EXPECT_EQ(black["row_cache"]["patches_without_row"].get<double>(), 16.0);
    EXPECT_EQ(black["sky"]["rows_computed"].get<double>(), 16.0);
    EXPECT_EQ(black["sky"]["rows_reused"].get<double>(), 16.0);
    // Rows from the .ffm (--matrix): the same again.
    r = run_ffcube("solve " + emitting_squares(dir) + " --max-patch-edge 0.25 -q --matrix " + (dir / "F.ffm") + " --sky " +
                   (dir / "matrix.csv"));
    ASSERT_EQ(r.code, 0) << r.output;
    EXPECT_EQ(read_text(dir / "matrix.csv"), ff);
    // With --sky-by object, the ray caster, and two threads against formfactors' one.
    const std::string rays = emitting_squares(dir) + " --max-patch-edge 0.5 --method raycast --rays 2000 -q --sky-by object --sky ";
    r = run_ffcube("solve " + rays + (dir / "rs.csv") + " --threads 2");
    ASSERT_EQ(r.code, 0) << r.output;
    r = run_ffcube("formfactors " + rays + (dir / "rf.csv") + " --threads 1");
    ASSERT_EQ(r.code, 0) << r.output;
    EXPECT_EQ(read_text(dir / "rs.csv"), read_text(dir / "rf.csv"));
}

TEST(SolveSky, AfterAdaptiveMeshingTheRowsAreThoseOfTheLastLevel) {
    TempDir dir;
    // --max-elements at the starting count: one adaptive level and no refinement, so the solve's
    // last scene is the starting mesh (32 patches) and its sky file must be formfactors' bytes.
    const std::string common = emitting_squares(dir) + " --max-patch-edge 0.25 --resolution 64 -q --sky ";
    auto r = run_ffcube("solve " + common + (dir / "solve.csv") + " --max-elements 32 --report " + (dir / "r.json"));
    ASSERT_EQ(r.code, 0) << r.output;
    const auto report = nlohmann::json::parse(read_text(dir / "r.json"));
    ASSERT_TRUE(report.contains("adaptive")) << r.output;
    r = run_ffcube("formfactors " + common + (dir / "ff.csv"));
    ASSERT_EQ(r.code, 0) << r.output;
    const std::string ff = read_text(dir / "ff.csv");
    EXPECT_EQ(last_column_by_first(ff).size(), 32u);
    EXPECT_EQ(read_text(dir / "solve.csv"), ff);
}

TEST(SolveSky, ObstructionOnlySurfacesAreTakenOffTheSky) {
    TempDir dir;
    // examples/lidded_box.vs3: the open box's opening is covered by an O lid, so nothing escapes
    // (without the lid the floor's SVF would be 0.19982, each wall's 0.20004).
    auto r = run_ffcube("solve " + example("lidded_box.vs3") + " --no-subdivide -q --sky " + (dir / "s.csv"));
    ASSERT_EQ(r.code, 0) << r.output;
    r = run_ffcube("formfactors " + example("lidded_box.vs3") + " --no-subdivide -q --sky " + (dir / "f.csv"));
    ASSERT_EQ(r.code, 0) << r.output;
    const std::string ff = read_text(dir / "f.csv");
    EXPECT_EQ(read_text(dir / "s.csv"), ff);
    const auto sky = last_column_by_first(ff);
    ASSERT_EQ(sky.size(), 5u);
    // Each row sums F over the four other faces plus the lid's intercepted share: exact analytic
    // values (a convex cavity), so 1 − Σ is 0 up to float32 rounding of five entries.
    for (const auto& [patch, v] : sky) EXPECT_NEAR(v, 0.0, 1e-6) << patch;

    // A .ffm does not record what the lid intercepts: --matrix with --sky is refused, exit 2.
    r = run_ffcube("formfactors " + example("lidded_box.vs3") + " --no-subdivide -q -o " + (dir / "F.ffm"));
    ASSERT_EQ(r.code, 0) << r.output;
    r = run_ffcube("solve " + example("lidded_box.vs3") + " --no-subdivide -q --matrix " + (dir / "F.ffm") + " --sky " +
                   (dir / "m.csv"));
    EXPECT_EQ(r.code, 2) << r.output;
    EXPECT_NE(r.output.find("--sky with --matrix"), std::string::npos) << r.output;
    EXPECT_NE(r.output.find("obstruction-only"), std::string::npos) << r.output;
    EXPECT_FALSE(std::filesystem::exists(dir / "m.csv"));
}

TEST(SolveSky, BadSkyOptionsAreRefusedBeforeWork) {
    auto r = run_ffcube("solve " + example("parallel_squares.obj") + " -q --sky /no/such/dir/s.csv");
    EXPECT_EQ(r.code, 2) << r.output;
    EXPECT_NE(r.output.find("--sky /no/such/dir/s.csv: the directory /no/such/dir does not exist"), std::string::npos)
        << r.output;
    r = run_ffcube("solve " + example("parallel_squares.obj") + " -q --sky s.csv --sky-by face");
    EXPECT_EQ(r.code, 2) << r.output;
    EXPECT_NE(r.output.find("--sky-by"), std::string::npos) << r.output;
}

}  // namespace
}  // namespace ffcube
