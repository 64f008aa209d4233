// The expert door (src/cli/expert.hpp): --help lists what a user needs (at most 20 options for
// formfactors), --help-all adds the tuning knobs, --set NAME=VALUE sets one and is the same as
// the knob's own spelling, and anything else through --set is refused with exit 2.
#include <gtest/gtest.h>

#include <sstream>
#include <string>
#include <vector>

#include "cli/cli_util.hpp"
#include "ffcube/io/ffm.hpp"

namespace ffcube {
namespace {

using test::run_ffcube;
using test::TempDir;

// The option lines of a CLI11 help text (those that start, after indentation, with a dash).
int option_lines(const std::string& help) {
    std::istringstream in(help);
    std::string line;
    int n = 0;
    while (std::getline(in, line)) {
        const auto k = line.find_first_not_of(' ');
        if (k != std::string::npos && k > 0 && line[k] == '-') ++n;
    }
    return n;
}

TEST(ExpertDoorCli, HelpListsAtMostTwentyOptionsAndHelpAllTheKnobs) {
    const auto help = run_ffcube("formfactors --help");
    ASSERT_EQ(help.code, 0) << help.output;
    EXPECT_LE(option_lines(help.output), 20) << help.output;
    EXPECT_EQ(help.output.find("--near-k"), std::string::npos) << help.output;
    EXPECT_NE(help.output.find("--set"), std::string::npos);
    EXPECT_NE(help.output.find("--help-all"), std::string::npos);
    const auto all = run_ffcube("formfactors --help-all");
    ASSERT_EQ(all.code, 0) << all.output;
    EXPECT_NE(all.output.find("--near-k"), std::string::npos) << all.output;
    EXPECT_NE(all.output.find("Tuning knobs"), std::string::npos);
    EXPECT_GT(option_lines(all.output), option_lines(help.output));
    // The viewer's scripting hooks are behind the same door.
    const auto view = run_ffcube("view --help");
    EXPECT_EQ(view.output.find("--screenshot"), std::string::npos) << view.output;
    EXPECT_NE(run_ffcube("view --help-all").output.find("--screenshot"), std::string::npos);
}

TEST(ExpertDoorCli, SetIsTheKnobItself) {
    TempDir dir;
    const std::string scene = test::example("parallel_squares.obj") + " --max-patch-edge 0.25 --resolution 32 -q";
    const auto a = run_ffcube("formfactors " + scene + " --set near-k=4 --set no-rotate -o " + (dir / "a.ffm"));
    ASSERT_EQ(a.code, 0) << a.output;
    const auto b = run_ffcube("formfactors " + scene + " --near-k 4 --no-rotate -o " + (dir / "b.ffm"));
    ASSERT_EQ(b.code, 0) << b.output;
    const auto c = run_ffcube("formfactors " + scene + " -o " + (dir / "c.ffm"));
    ASSERT_EQ(c.code, 0) << c.output;
    EXPECT_EQ(test::read_text(dir / "a.ffm"), test::read_text(dir / "b.ffm"));
    // The knobs took effect: the settings the .ffm records are not the defaults'.
    const FfmFile fa = read_ffm(dir / "a.ffm"), fc = read_ffm(dir / "c.ffm");
    EXPECT_NE(fa.meta.settings.find("rotate=0"), std::string::npos) << fa.meta.settings;
    EXPECT_NE(fa.meta.settings.find("k=4"), std::string::npos) << fa.meta.settings;
    EXPECT_NE(fa.meta.settings, fc.meta.settings);
}

TEST(ExpertDoorCli, SetRefusesWhatIsNotAKnob) {
    TempDir dir;
    for (const std::string& bad :
         std::vector<std::string>{"--set output=" + (dir / "x.ffm"), "--set no-such-knob=1", "--set", "--set =3"}) {
        const auto r = run_ffcube("formfactors " + test::example("parallel_squares.obj") + " -q " + bad);
        EXPECT_EQ(r.code, 2) << bad << "\n" << r.output;
        EXPECT_NE(r.output.find("--set"), std::string::npos) << r.output;
        EXPECT_FALSE(std::filesystem::exists(dir / "x.ffm"));
    }
    const auto r = run_ffcube("formfactors " + test::example("parallel_squares.obj") + " --set no-such-knob=1");
    EXPECT_NE(r.output.find("not a tuning knob"), std::string::npos) << r.output;
    EXPECT_NE(r.output.find("near-k"), std::string::npos) << r.output;  // the list of knobs
}

}  // namespace
}  // namespace ffcube
