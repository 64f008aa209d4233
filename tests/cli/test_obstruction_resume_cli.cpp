// Checkpoints of scenes with obstruction-only surfaces (View3D's O, and the null N and masking M
// surfaces, which block as obstructions; Scene::drawn): each row's obstructed share is stored with
// it (io/checkpoint.hpp, format 2), so a run interrupted part-way and resumed writes F, --sky,
// --view3d and --elmer byte-identical to an uninterrupted run.
//
// The interruption: a SIGKILL leaves the checkpoint's log as a prefix of the uninterrupted run's
// records, possibly ending in a torn record (docs/robustness.md). With --no-subdivide these scenes
// have 3 to 5 rows that take milliseconds, too few to kill reliably in flight, so those tests make
// the states directly: a finished checkpoint's log cut at record boundaries and inside records,
// each then resumed. One test kills a meshed lidded box (1,445 rows) with SIGKILL, as
// test_resume_cli.cpp does.
#include <gtest/gtest.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <filesystem>
#include <thread>
#include <string>
#include <vector>

#include "cli/cli_util.hpp"
#include "support/view3d_text.hpp"

namespace fs = std::filesystem;

namespace ffcube {
namespace {

using test::read_text;
using test::run_ffcube;
using test::run_ffcube_env;
using test::TempDir;

const std::vector<std::string> kOutputs = {"F.ffm", "sky.csv", "vf.txt", "vf.dat"};

std::string outputs(const TempDir& dir, const std::string& prefix, bool matrix = true) {
    return (matrix ? " -o " + (dir / (prefix + "F.ffm")) : std::string()) + " --sky " + (dir / (prefix + "sky.csv")) + " --view3d " +
           (dir / (prefix + "vf.txt")) + " --elmer " + (dir / (prefix + "vf.dat"));
}

// Runs `scene` plainly, then with a checkpoint whose log is cut at several points (each a state a
// kill leaves) and resumed; every output of every resumed run must be the plain run's bytes.
// matrix: the resumed runs write F too (else they hold the rows in memory, and write the rest).
void expect_resumes_byte_identical(const std::string& scene, bool matrix = true) {
    TempDir dir;
    const std::string job = "formfactors " + scene + " --no-subdivide -q";
    const auto plain = run_ffcube(job + outputs(dir, "plain-"));
    ASSERT_EQ(plain.code, 0) << plain.output;
    const auto full = run_ffcube(job + outputs(dir, "full-") + " --checkpoint " + (dir / "ck"));
    ASSERT_EQ(full.code, 0) << full.output;
    EXPECT_NE(read_text(fs::path(dir / "ck") / "manifest.txt").find("obstructions 1"), std::string::npos);
    const std::string log = read_text(fs::path(dir / "ck") / "rows.log");
    ASSERT_GT(log.size(), 0u);
    for (const std::string& out : kOutputs) EXPECT_TRUE(read_text(dir / ("full-" + out)) == read_text(dir / ("plain-" + out))) << out;
    // Cut points: nothing kept, the first record torn (13 bytes: inside its header), about half,
    // and all but the last 8 bytes (the last record's checksum torn).
    for (const std::size_t keep : {std::size_t{0}, std::size_t{13}, log.size() / 2, log.size() - 8}) {
        SCOPED_TRACE("log cut to " + std::to_string(keep) + " of " + std::to_string(log.size()) + " bytes");
        const std::string ck = dir / ("ck-" + std::to_string(keep));
        fs::create_directory(ck);
        fs::copy_file(fs::path(dir / "ck") / "manifest.txt", fs::path(ck) / "manifest.txt");
        test::write_file((fs::path(ck) / "rows.log").string(), log.substr(0, keep));
        const std::string prefix = "r" + std::to_string(keep) + "-";
        const auto resumed =
            run_ffcube(job + outputs(dir, prefix, matrix) + " --checkpoint " + ck + " --resume");
        ASSERT_EQ(resumed.code, 0) << resumed.output;
        for (const std::string& out : kOutputs) {
            if (!matrix && out == "F.ffm") {
                EXPECT_FALSE(fs::exists(dir / (prefix + out)));
                continue;
            }
            EXPECT_TRUE(read_text(dir / (prefix + out)) == read_text(dir / ("plain-" + out))) << out << " differs";
        }
    }
}

TEST(ObstructionResumeCli, LiddedBoxResumesToTheUninterruptedBytes) {
    expect_resumes_byte_identical(test::example("lidded_box.vs3"));
}

// Resumed without an output file (the rows held in memory for the statistics): the sky, View3D's
// and Elmer's files are still the uninterrupted run's bytes.
TEST(ObstructionResumeCli, LiddedBoxResumesWithoutAnOutputFileToo) {
    expect_resumes_byte_identical(test::example("lidded_box.vs3"), /*matrix=*/false);
}

// A null surface (a hole) and a masking surface over a square of a wall facing another wall
// (tests/cli/test_view3d_subsurfaces_cli.cpp's scenes): both become obstructions.
TEST(ObstructionResumeCli, NullAndMaskSurfacesResumeToTheUninterruptedBytes) {
    for (const std::string square : {"N 2 8 7 6 5 1 0 0.9 hole", "M 2 8 7 6 5 1 0 0.5 mask"}) {
        SCOPED_TRACE(square);
        TempDir dir;
        test::write_file(dir / "w.vs3", "T wall\n" + std::string(test::kVs3WindowWallVertices) +
                                            "V 9 0 0 1\nV 10 2 0 1\nV 11 2 2 1\nV 12 0 2 1\nS 1 1 2 3 4 0 0 0.9 wall\n" + square +
                                            "\nS 3 9 12 11 10 0 0 0.9 opposite\nEnd\n");
        expect_resumes_byte_identical(dir / "w.vs3");
    }
}

// The lidded box meshed (1,445 rows at 64², about a second of one worker on llvmpipe), killed with
// SIGKILL once some rows (records of about 9 KB) are in the log, then resumed.
TEST(ObstructionResumeCli, KilledMeshedLiddedBoxResumesToTheUninterruptedBytes) {
    TempDir dir;
    const std::string job = "formfactors " + test::example("lidded_box.vs3") + " --patches 2000 --resolution 64 --threads 1 -q";
    const std::string ck = dir / "ck";
    const fs::path rows = fs::path(ck) / "rows.log";
    const std::string killed = test::kill_when_file_reaches(job + outputs(dir, "killed-") + " --checkpoint " + ck, rows, 64 * 1024);
    ASSERT_EQ(killed, "");
    EXPECT_FALSE(fs::exists(dir / "killed-F.ffm"));

    const auto resumed = run_ffcube(job + outputs(dir, "resumed-") + " --checkpoint " + ck + " --resume");
    ASSERT_EQ(resumed.code, 0) << resumed.output;
    const auto plain = run_ffcube(job + outputs(dir, "plain-"));
    ASSERT_EQ(plain.code, 0) << plain.output;
    for (const std::string& out : kOutputs)
        EXPECT_TRUE(read_text(dir / ("resumed-" + out)) == read_text(dir / ("plain-" + out))) << out << " differs";
}

// A checkpoint made for the scene without its obstruction is not resumed by the scene with it:
// the rows differ (the fingerprint is the whole scene's) and so does the record layout.
TEST(ObstructionResumeCli, CheckpointOfTheOpenBoxIsRefusedForTheLiddedOne) {
    TempDir dir;
    const auto open = run_ffcube("formfactors " + test::example("open_box.vs3") + " --no-subdivide -q -o " + (dir / "a.ffm") +
                                 " --checkpoint " + (dir / "ck"));
    ASSERT_EQ(open.code, 0) << open.output;
    const auto lidded = run_ffcube("formfactors " + test::example("lidded_box.vs3") + " --no-subdivide -q -o " +
                                   (dir / "b.ffm") + " --checkpoint " + (dir / "ck") + " --resume");
    EXPECT_EQ(lidded.code, 2) << lidded.output;
    EXPECT_NE(lidded.output.find("obstructions: checkpoint '0', this run '1'"), std::string::npos) << lidded.output;
    EXPECT_FALSE(fs::exists(dir / "b.ffm"));
}

}  // namespace
}  // namespace ffcube
