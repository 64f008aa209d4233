// Accuracy by target end to end (issue 40, docs/accuracy.md "Accuracy by target"): --tolerance and a
// .vs3's eps are checked and recorded, ray-cast rows are refined to the target and meet it against
// the closed form, the report and the patch table carry the estimates.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>

#include "cli/cli_util.hpp"
#include "ffcube/io/ffm.hpp"

namespace ffcube {
namespace {

using test::run_ffcube;
using test::TempDir;

TEST(ToleranceCli, TargetsDoublePrecisionCannotHonourAreRefusedWithNoOutput) {
    TempDir dir;
    for (const std::string bad : {"0", "-1e-3", "1e-10", "1", "nan", "inf"}) {
        const auto r = run_ffcube("formfactors " + test::example("parallel_squares.obj") + " -q --tolerance " + bad +
                                  " -o " + (dir / "F.ffm"));
        EXPECT_EQ(r.code, 2) << bad << ": " << r.output;
        EXPECT_NE(r.output.find("--tolerance"), std::string::npos) << r.output;
        EXPECT_FALSE(std::filesystem::exists(dir / "F.ffm")) << bad;
    }
}

// examples/parallel_squares.vs3 with its control line replaced.
std::string squares_vs3(const TempDir& dir, const std::string& controls) {
    std::string text = test::read_text(test::example("parallel_squares.vs3"));
    const std::size_t at = text.find("C encl=0 emit=0");
    text.replace(at, std::string("C encl=0 emit=0").size(), controls);
    const std::string path = dir / "squares.vs3";
    test::write_file(path, text);
    return path;
}

TEST(ToleranceCli, AVs3EpsSetsTheTargetUnlessTheCommandLineDoes) {
    TempDir dir;
    const std::string vs3 = squares_vs3(dir, "C encl=0 emit=0 eps=2e-3");
    auto r = run_ffcube("formfactors " + vs3 + " -q --report " + (dir / "a.json"));
    ASSERT_EQ(r.code, 0) << r.output;
    auto j = nlohmann::json::parse(test::read_text(dir / "a.json"));
    EXPECT_DOUBLE_EQ(j["tolerance"]["target"].get<double>(), 2e-3);
    EXPECT_DOUBLE_EQ(j["view3d"]["eps"].get<double>(), 2e-3);
    r = run_ffcube("formfactors " + vs3 + " -q --tolerance 5e-3 --report " + (dir / "b.json"));
    ASSERT_EQ(r.code, 0) << r.output;
    j = nlohmann::json::parse(test::read_text(dir / "b.json"));
    EXPECT_DOUBLE_EQ(j["tolerance"]["target"].get<double>(), 5e-3);
    // An eps below what double precision honours: refused, naming the file and its line (2).
    const std::string bad = squares_vs3(dir, "C encl=0 emit=0 eps=1e-12");
    r = run_ffcube("view3d " + bad + " " + (dir / "vf.txt"));
    EXPECT_EQ(r.code, 2) << r.output;
    EXPECT_NE(r.output.find("squares.vs3:2"), std::string::npos) << r.output;
    EXPECT_NE(r.output.find("eps=1e-12"), std::string::npos) << r.output;
    EXPECT_FALSE(std::filesystem::exists(dir / "vf.txt"));
}

TEST(ToleranceCli, RayRowsAreRefinedToTheTargetAndMeetTheClosedForm) {
    TempDir dir;
    const double E = 1e-3;
    const auto r = run_ffcube("formfactors " + test::example("perpendicular_squares.obj") +
                              " --max-patch-edge 0.25 --method raycast -q --tolerance 1e-3 -o " + (dir / "F.ffm") +
                              " --groups " + (dir / "g.csv") + " --report " + (dir / "r.json") + " --patch-table " +
                              (dir / "p.csv"));
    ASSERT_EQ(r.code, 0) << r.output;
    const auto j = nlohmann::json::parse(test::read_text(dir / "r.json"));
    EXPECT_TRUE(j["tolerance"]["rows_refined"].get<bool>());
    EXPECT_EQ(j["tolerance"]["rows"], 32);
    EXPECT_GE(j["rays_per_patch_mean"].get<double>(), 4096.0);  // tolerance_rays(1e-3).least
    // Square a sees only square b, so each of a's rows sums to its share of b: the object value
    // is an area-weighted mean of row sums, each within E by its estimate (97.5% each, and the
    // errors of 16 rows average down), so within E. Closed form: two unit squares at 90°, 0.2000438.
    std::istringstream groups(test::read_text(dir / "g.csv"));
    std::string line;
    double floor_to_wall = NAN;
    while (std::getline(groups, line))
        if (line.rfind("a,b,", 0) == 0) floor_to_wall = std::stod(line.substr(4));
    EXPECT_NEAR(floor_to_wall, 0.2000438, E);
    // The patch table's last column: each row's estimate; the rows above the target are the
    // report's count (a row stops above it only when its budget of 64/E rays is spent).
    std::istringstream table(test::read_text(dir / "p.csv"));
    std::getline(table, line);
    EXPECT_EQ(line, "patch,object,area,cx,cy,cz,nx,ny,nz,error_estimate");
    int rows = 0, above = 0;
    double largest = 0;
    while (std::getline(table, line)) {
        const double e = std::stod(line.substr(line.rfind(',') + 1));
        EXPECT_GT(e, 0.0) << line;
        above += e > E;
        largest = std::max(largest, e);
        ++rows;
    }
    EXPECT_EQ(rows, 32);
    EXPECT_EQ(j["tolerance"]["rows_above"].get<int>(), above);
    EXPECT_EQ(j["rows_at_ray_budget"].get<int>(), above);
    // The table prints 3 significant digits: within half a unit of the third, 5e-3 relative.
    EXPECT_NEAR(j["tolerance"]["estimate_max"].get<double>(), largest, 5e-3 * largest);
    EXPECT_LE(above, 8);  // most rows meet it (the pairs along the shared edge are exact: near values)
    // Recorded with the matrix: a checkpoint or matrix of another target is another matrix.
    EXPECT_NE(read_ffm(dir / "F.ffm").meta.settings.find("tolerance=0.001"), std::string::npos);
}

TEST(ToleranceCli, AFixedRayCountSaysTheTargetIsNotGuaranteed) {
    TempDir dir;
    const auto r = run_ffcube("formfactors " + test::example("perpendicular_squares.obj") +
                              " --max-patch-edge 0.25 --method raycast --set rays=256 --tolerance 1e-3 --report " +
                              (dir / "r.json"));
    ASSERT_EQ(r.code, 0) << r.output;
    const auto j = nlohmann::json::parse(test::read_text(dir / "r.json"));
    EXPECT_FALSE(j["tolerance"]["rows_refined"].get<bool>());
    EXPECT_EQ(j["tolerance"]["not_refined_because"], "--rays fixes the ray count");
    // 256 rays cannot make 1e-3 (the binomial noise alone is about 0.02 on these rows): the rows
    // above the target are counted and said.
    EXPECT_GT(j["tolerance"]["rows_above"].get<int>(), 0);
    EXPECT_NE(r.output.find("have an estimated error above it"), std::string::npos) << r.output;
}

}  // namespace
}  // namespace ffcube
