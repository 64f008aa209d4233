// `ffcube bench --scene FILE` end to end: the sweep's outputs are written for a scene of one's
// own; a scene that cannot be read is refused with its name, exit 2 and no output directory.
#include <gtest/gtest.h>

#include <filesystem>
#include <sstream>
#include <string>

#include "cli/cli_util.hpp"

namespace ffcube {
namespace {

using test::run_ffcube;
using test::TempDir;

// examples/parallel_squares.obj: two unit squares, one patch each under --scene (one patch a
// face), so the sample is both rows and the CSV has one line, the target's. What the errors and
// estimates must satisfy is BenchScene.SweepCarriesEstimatesThatBoundTheErrorAgainstManyRays;
// here, the command's wiring.
TEST(BenchCli, SceneSweepWritesItsResults) {
    TempDir dir;
    const std::string out = dir / "sweep";
    const auto r = run_ffcube("bench --scene " + test::example("parallel_squares.obj") + " --tolerances 1e-2 --threads 2 --out " + out);
    ASSERT_EQ(r.code, 0) << r.output;
    EXPECT_NE(r.output.find("2 patches; 2 sampled rows"), std::string::npos) << r.output;
    for (const char* f : {"results.csv", "results.json", "error_vs_time.svg", "error_vs_time.png"})
        EXPECT_TRUE(std::filesystem::exists(std::filesystem::path(out) / f)) << f;
    std::istringstream csv(test::read_text(std::filesystem::path(out) / "results.csv"));
    std::string header, line, extra;
    std::getline(csv, header);
    ASSERT_TRUE(std::getline(csv, line));
    EXPECT_FALSE(std::getline(csv, extra));
    EXPECT_EQ(line.rfind("parallel_squares,scene,auto@tolerance,E=0.01,", 0), 0u) << line;
}

TEST(BenchCli, UnreadableSceneIsRefusedWithoutOutput) {
    TempDir dir;
    const std::string out = dir / "sweep";
    const auto r = run_ffcube("bench --scene " + (dir / "missing.stl") + " --out " + out);
    EXPECT_EQ(r.code, 2) << r.output;
    EXPECT_NE(r.output.find("missing.stl"), std::string::npos) << r.output;
    EXPECT_FALSE(std::filesystem::exists(out));
}

}  // namespace
}  // namespace ffcube
