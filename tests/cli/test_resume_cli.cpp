// Resumable precomputation end to end: `ffcube formfactors ... --checkpoint DIR` killed with
// SIGKILL part-way, then the same command with --resume, writes a .ffm, a patch table (with each
// row's estimate) and per-row report figures identical to an uninterrupted run's; a resume with
// different settings is refused.
#include <gtest/gtest.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <filesystem>
#include <thread>
#include <vector>

#include "cli/cli_util.hpp"

namespace fs = std::filesystem;

namespace ffcube {
namespace {

using test::run_ffcube;
using test::TempDir;

// The job: big enough that it is still running when killed (2000 hemicubes at 64² on one worker
// take about a second on llvmpipe, and the kill comes after a few rows), small enough for a test.
std::string job(const TempDir& dir, const std::string& output, const std::string& extra = "") {
    return "formfactors " + test::example("cube.obj") + " --patches 2000 --resolution 64 --threads 1 -q -o " +
           (dir / output) + " " + extra;
}

TEST(ResumeCli, KilledRunResumesToByteIdenticalMatrix) {
    TempDir dir;
    const std::string ck = dir / "ck";
    const std::string log = dir / "rows.log";

    // Start the checkpointed run and kill -9 it once some rows (but not all) are in the log. A
    // row record at 64² is about 10 KB; 64 KB of log is a handful of rows out of 2000.
    const fs::path rows = fs::path(ck) / "rows.log";
    const std::string killed = test::kill_when_file_reaches(job(dir, "killed.ffm", "--checkpoint " + ck), rows, 64 * 1024);
    ASSERT_EQ(killed, "");
    // Worker processes die with their parent's pipes; the log no longer grows once the writer (the
    // parent) is gone.
    EXPECT_FALSE(fs::exists(dir / "killed.ffm"));  // atomic output: nothing half-written
    const auto killed_size = fs::file_size(rows);

    // A resume with other settings is refused, naming the setting, and writes nothing.
    const auto bad = run_ffcube(job(dir, "other.ffm", "--checkpoint " + ck + " --resume --no-rotate"));
    EXPECT_EQ(bad.code, 2) << bad.output;
    EXPECT_NE(bad.output.find("settings: checkpoint 'rotate=1"), std::string::npos) << bad.output;
    EXPECT_FALSE(fs::exists(dir / "other.ffm"));
    // Starting a new checkpoint over it is refused too: finished rows are never thrown away.
    const auto again = run_ffcube(job(dir, "other.ffm", "--checkpoint " + ck));
    EXPECT_EQ(again.code, 2) << again.output;
    EXPECT_NE(again.output.find("already holds a checkpoint"), std::string::npos) << again.output;

    // Each reused row's estimates come back from its record with it (format 3): the patch
    // table's error column and the report's per-row figures are the uninterrupted run's.
    const auto resumed = run_ffcube(job(dir, "resumed.ffm",
                                        "--checkpoint " + ck + " --resume --report " + (dir / "r.json") +
                                            " --patch-table " + (dir / "resumed.csv")));
    ASSERT_EQ(resumed.code, 0) << resumed.output;
    const std::string report = test::read_text(dir / "r.json");
    // At least the rows whose records were whole when killed were reused (a torn last record is not).
    const auto pos = report.find("\"rows_reused\":");
    ASSERT_NE(pos, std::string::npos) << report;
    const long reused = std::stol(report.substr(pos + 14));
    EXPECT_GT(reused, 0);
    EXPECT_LT(reused, 2000);
    EXPECT_GE(fs::file_size(rows), killed_size);

    const auto plain = run_ffcube(job(dir, "plain.ffm", "--report " + (dir / "p.json") + " --patch-table " + (dir / "plain.csv")));
    ASSERT_EQ(plain.code, 0) << plain.output;
    const std::string a = test::read_text(dir / "resumed.ffm"), b = test::read_text(dir / "plain.ffm");
    EXPECT_GT(a.size(), 0u);
    EXPECT_TRUE(a == b) << "resumed " << a.size() << " bytes, uninterrupted " << b.size() << " bytes";
    const std::string table = test::read_text(dir / "plain.csv");
    EXPECT_NE(table.find(",error_estimate\n"), std::string::npos) << table.substr(0, 200);
    EXPECT_TRUE(test::read_text(dir / "resumed.csv") == table) << "the patch tables differ";
    // The per-row arrays of the report (row_error_estimate.rows, corrections.row_measure), from
    // their key to the end of the array (no other key of these names holds an array).
    const auto array = [](const std::string& json, const std::string& key) {
        const auto at = json.find("\"" + key + "\": [");  // Report::dump indents by 2
        return at == std::string::npos ? std::string("(missing)") : json.substr(at, json.find(']', at) - at);
    };
    const std::string plain_report = test::read_text(dir / "p.json");
    for (const char* key : {"rows", "row_measure"})
        EXPECT_EQ(array(report, key), array(plain_report, key)) << key;
}

TEST(ResumeCli, ResumeNeedsACheckpointDirectory) {
    TempDir dir;
    const auto r = run_ffcube("formfactors " + test::example("cube.obj") + " --max-patch-edge 0.5 -q --resume -o " +
                              (dir / "F.ffm"));
    EXPECT_EQ(r.code, 2) << r.output;
    EXPECT_NE(r.output.find("--resume requires --checkpoint"), std::string::npos) << r.output;
    const auto none = run_ffcube("formfactors " + test::example("cube.obj") + " --max-patch-edge 0.5 -q --resume " +
                                 "--checkpoint " + (dir / "nothing") + " -o " + (dir / "F.ffm"));
    EXPECT_EQ(none.code, 2) << none.output;
    EXPECT_NE(none.output.find("holds no checkpoint"), std::string::npos) << none.output;
    EXPECT_FALSE(fs::exists(dir / "F.ffm"));
}

}  // namespace
}  // namespace ffcube
