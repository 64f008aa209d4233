// Messages name what the user wrote (issue 43, part 4): a .vs3's encl=1 in an open scene is
// refused naming the file and its C line (the user never wrote --enforce), and a materials CSV
// value that no solve can take (Kd = 1) is refused naming the CSV's line, not the scene file.
#include <gtest/gtest.h>

#include <filesystem>
#include <regex>
#include <string>

#include "cli/cli_util.hpp"

namespace ffcube {
namespace {

using test::run_ffcube;
using test::TempDir;

TEST(MessagesCli, EnclInAnOpenVs3NamesTheFileAndItsControlLine) {
    TempDir dir;
    // examples/open_box.vs3 with its C line (line 2) switched to encl=1: five faces, no lid, so
    // the floor's row sums to about 0.8 and closure is impossible.
    std::string box = test::read_text(test::example("open_box.vs3"));
    const std::size_t c = box.find("C encl=0");
    ASSERT_NE(c, std::string::npos);
    box.replace(c, 8, "C encl=1");
    const std::string in = dir / "open.vs3";
    test::write_file(in, box);
    const auto r = run_ffcube("formfactors " + in + " --no-subdivide -q -o " + (dir / "F.ffm"));
    EXPECT_EQ(r.code, 2) << r.output;
    EXPECT_NE(r.output.find(in + ":2: encl=1"), std::string::npos) << r.output;
    EXPECT_NE(r.output.find("which the command line did not give"), std::string::npos) << r.output;
    EXPECT_NE(r.output.find("open"), std::string::npos) << r.output;  // the reason: light escapes
    EXPECT_FALSE(std::filesystem::exists(dir / "F.ffm"));
}

TEST(MessagesCli, KdOfOneInAMaterialsCsvNamesTheCsvLine) {
    TempDir dir;
    const std::string csv = dir / "m.csv";
    // Line 3 gives the floor a reflectance of 1 in the green channel.
    test::write_file(csv, "object,kd_r,kd_g,kd_b,ke_r,ke_g,ke_b\nx0,0.5,0.5,0.5,,,\nz0,0.5,1,0.5,,,\n");
    const auto r = run_ffcube("solve " + test::example("closed_cube.stl") + " --no-subdivide --materials " + csv +
                              " -q --objects " + (dir / "o.csv"));
    EXPECT_EQ(r.code, 2) << r.output;
    EXPECT_NE(r.output.find(csv + ":3: Kd 1 must be within [0,1)"), std::string::npos) << r.output;
    EXPECT_FALSE(std::filesystem::exists(dir / "o.csv"));
    // Just below 1 is a material a solve takes (a stiff one).
    test::write_file(csv, "object,kd_r,kd_g,kd_b,ke_r,ke_g,ke_b\nz0,0.5,0.99,0.5,1,1,1\n");
    const auto ok = run_ffcube("solve " + test::example("closed_cube.stl") + " --no-subdivide --materials " + csv +
                               " -q --objects " + (dir / "o.csv"));
    EXPECT_EQ(ok.code, 0) << ok.output;
}

}  // namespace
}  // namespace ffcube
