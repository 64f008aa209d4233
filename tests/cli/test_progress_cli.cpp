// Every phase of `ffcube formfactors` and `ffcube solve` that can run for long at large n shows a
// progress line (docs/robustness.md, "Progress"): on small runs with FFCUBE_PROGRESS=always,
// which makes each bar print its first step and its end however short the run, each phase's line
// is there, and a bar line carries an ETA, or says the ETA is not known yet, or how long it took.
#include <gtest/gtest.h>

#include <regex>
#include <sstream>

#include "cli/cli_util.hpp"

namespace ffcube {
namespace {

// Lines of a bar: "WHAT: done/total (p%), r/s, ETA s s" | "ETA soon known" | "took s s".
void expect_bar(const std::string& output, const std::string& what) {
    std::istringstream in(output);
    std::string line;
    bool started = false, finished = false;
    const std::regex bar(R"(: \d+/\d+ \(\d+\.\d%\), \d+\.\d/s, (ETA \d+ s|ETA soon known|took \d+ s)$)");
    while (std::getline(in, line)) {
        if (line.rfind(what, 0) != 0) continue;
        EXPECT_TRUE(std::regex_search(line, bar)) << line;
        (line.find("took") != std::string::npos ? finished : started) = true;
    }
    EXPECT_TRUE(started) << "no first line of \"" << what << "\" in:\n" << output;
    EXPECT_TRUE(finished) << "no last line of \"" << what << "\" in:\n" << output;
}

TEST(ProgressCli, EveryPhaseShowsItsLine) {
    test::TempDir dir;
    const std::string env = "FFCUBE_PROGRESS=always ";
    // A closed cube (closure applies), --stats-memory 1: several bands of the transpose.
    const std::string cube = test::example("closed_cube.stl") + " --max-patch-edge 0.25 --resolution 16";
    auto r = test::run_ffcube_env(env, "formfactors " + cube + " --enforce closure --stats-memory 1 -o " +
                                           (dir / "F.mtx") + " --elmer " + (dir / "F.dat"));
    ASSERT_EQ(r.code, 0) << r.output;
    expect_bar(r.output, "rows: ");
    expect_bar(r.output, "--enforce closure: rows with columns (2 passes, ");
    expect_bar(r.output, "--enforce closure: scaling iteration 1 (a pass over G): ");
    expect_bar(r.output, "--enforce closure: writing the enforced rows (a pass over G): ");
    expect_bar(r.output, "writing " + (dir / "F.mtx") + " (MiB of entries after the header): ");
    // Closure's iterations: one line each here, with the error and, from the second on, an ETA.
    EXPECT_NE(r.output.find("ffcube: --enforce closure: scaling iteration 2 (a pass over G): max |row sum - 1| "),
              std::string::npos)
        << r.output;
    EXPECT_TRUE(std::regex_search(r.output, std::regex(R"(scaling iteration \d+ .*converged)"))) << r.output;

    // Without --enforce: the reciprocity check while the rows come. About 1.2e5 entries, of
    // which fewer than the 65,536 that 1 MiB holds (16 bytes each) wait for their column's row
    // at any time: no pass over the file follows, and the line says so.
    r = test::run_ffcube_env(env, "formfactors " + cube + " --stats-memory 1 -o " + (dir / "F.ffm"));
    ASSERT_EQ(r.code, 0) << r.output;
    expect_bar(r.output, "rows: ");
    EXPECT_NE(r.output.find("ffcube: reciprocity: checked while the rows came ("), std::string::npos) << r.output;
    EXPECT_EQ(r.output.find("reciprocity (1 pass"), std::string::npos) << r.output;
    // The cube at 0.125: 1,536 patches, about 2e6 entries, some 5e5 of them waiting at the middle
    // rows: past 1 MiB, so the check gives up and reads the file, by bands of 131,072 entries.
    const std::string fine = test::example("closed_cube.stl") + " --max-patch-edge 0.125 --resolution 16";
    r = test::run_ffcube_env(env, "formfactors " + fine + " --stats-memory 1 -o " + (dir / "F2.ffm"));
    ASSERT_EQ(r.code, 0) << r.output;
    expect_bar(r.output, "reciprocity (2 passes over F2.ffm, ");

    // No output file: the rows as computed are held in memory, and --enforce's passes read them there.
    r = test::run_ffcube_env(env, "formfactors " + cube + " --enforce reciprocity --groups " + (dir / "G.csv"));
    ASSERT_EQ(r.code, 0) << r.output;
    expect_bar(r.output, "rows: ");
    expect_bar(r.output, "--enforce reciprocity: rows with columns (");

    // solve from a matrix file: reading it is announced before it starts.
    ASSERT_EQ(test::run_ffcube("formfactors --patches 200 --resolution 16 -q -o " + (dir / "H.ffm")).code, 0);
    r = test::run_ffcube_env(env, "solve --patches 200 --resolution 16 --matrix " + (dir / "H.ffm"));
    ASSERT_EQ(r.code, 0) << r.output;
    EXPECT_NE(r.output.find("ffcube: reading " + (dir / "H.ffm") + " (the whole matrix"), std::string::npos) << r.output;
    // The solver's lines (every batch under FFCUBE_PROGRESS=always): the first has no decay to
    // measure yet; the later ones an ETA from the unshot fraction's decay since the line before.
    EXPECT_NE(r.output.find(" of emitted (target 1e-04), "), std::string::npos) << r.output;
    EXPECT_NE(r.output.find(" s, ETA not known yet"), std::string::npos) << r.output;
    EXPECT_TRUE(std::regex_search(r.output, std::regex(R"(\d+ shots, unshot \S+ of emitted \(target 1e-04\), \d+\.\d s, ETA \d+ s)")))
        << r.output;
}

}  // namespace
}  // namespace ffcube
