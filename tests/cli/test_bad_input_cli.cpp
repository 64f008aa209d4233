// Issue 6's bad-input suite through the command line: every bad scene given to
// `ffcube formfactors SCENE -o F.ffm --groups G.csv --report R.json` ends with its message (file,
// line and rule), exit code 2 (bad input) and none of the three output files, nor a temporary,
// left behind. The loader's own tests (tests/scene/test_obj_loader.cpp) check the same files at
// the library level; these check that nothing between the loader and the exit loses the error or
// writes a file first.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "cli/cli_util.hpp"
#include "cli/rusage_util.hpp"

namespace fs = std::filesystem;

namespace ffcube {
namespace {

using test::run_ffcube;
using test::TempDir;

const fs::path kBad = fs::path(FFCUBE_SOURCE_DIR) / "tests" / "data" / "scenes" / "bad";

struct Outcome {
    int code = -1;
    std::string output;
    std::vector<std::string> files_left;  // whatever is in the output directory afterwards
};

// Runs formfactors on scene with all three outputs in a fresh directory.
Outcome run_bad(const std::string& scene, const std::string& extra = "") {
    TempDir dir;
    const auto r = run_ffcube("formfactors '" + scene + "' -q --resolution 16 -o " + (dir / "F.ffm") + " --groups " +
                              (dir / "G.csv") + " --report " + (dir / "R.json") + " " + extra);
    Outcome o{r.code, r.output, {}};
    for (const auto& e : fs::directory_iterator(dir.path())) o.files_left.push_back(e.path().filename().string());
    return o;
}

void expect_refused(const Outcome& o, const std::string& message) {
    EXPECT_EQ(o.code, 2) << o.output.substr(0, 500);
    EXPECT_NE(o.output.find(message), std::string::npos) << "expected: " << message << "\ngot: " << o.output.substr(0, 500);
    EXPECT_TRUE(o.files_left.empty()) << "left behind: " << o.files_left.front();
}

struct BadCase {
    const char* file;
    const char* message;  // expected substring: file, line and the rule broken
};

class BadSceneCli : public testing::TestWithParam<BadCase> {};

TEST_P(BadSceneCli, RefusedWithMessageExit2AndNoOutput) {
    const BadCase c = GetParam();
    expect_refused(run_bad((kBad / c.file).string()), c.message);
}

INSTANTIATE_TEST_SUITE_P(
    Issue6, BadSceneCli,
    testing::Values(BadCase{"empty.obj", "empty.obj: no faces: the scene has no geometry"},
                    BadCase{"comments_only.obj", "comments_only.obj: no faces: the scene has no geometry"},
                    BadCase{"index_zero.obj", "index_zero.obj:6: face index 0 is invalid (OBJ indices start at 1)"},
                    BadCase{"index_out_of_range.obj", "index_out_of_range.obj:5: face index 9 is out of range (the file defines 4 vertices)"},
                    BadCase{"negative_index_before_start.obj", "negative_index_before_start.obj:5: face index -5 is out of range"},
                    BadCase{"nan_coordinate.obj", "nan_coordinate.obj:2: 'nan' is not a finite number"},
                    BadCase{"inf_coordinate.obj", "inf_coordinate.obj:3: '-inf' is not a finite number"},
                    BadCase{"overflow_float.obj", "overflow_float.obj:2: '1e39' is too large"},
                    BadCase{"truncated.obj", "truncated.obj:6: 'v' needs 3 coordinates, found 2"},
                    BadCase{"two_vertex_face.obj", "two_vertex_face.obj:6: a face needs at least 3 vertices, this one has 2"},
                    BadCase{"degenerate_only.obj", "degenerate_only.obj: no faces with non-zero area (all 3 faces are degenerate)"},
                    BadCase{"kd_above_one.obj", "kd_above_one.mtl:3: Kd '1.5' must be within [0,1]"},
                    BadCase{"kd_negative.obj", "kd_negative.mtl:2: Kd '-0.1' must be within [0,1]"},
                    BadCase{"ke_negative.obj", "ke_negative.mtl:3: Ke '-2' must be >= 0"},
                    BadCase{"ke_nan.obj", "ke_nan.mtl:2: 'NaN' is not a finite number (Ke"}),
    [](const testing::TestParamInfo<BadCase>& case_info) {
        const std::string name = case_info.param.file;
        return name.substr(0, name.find('.'));
    });

// Generated cases: too big or too binary to keep in the repository.
class GeneratedScene : public testing::Test {
protected:
    std::string write(const std::string& name, const std::string& bytes) {
        const std::string p = dir_ / name;
        std::ofstream(p, std::ios::binary) << bytes;
        return p;
    }
    TempDir dir_;
};

TEST_F(GeneratedScene, MegabyteGarbageToken) {
    const std::string p = write("huge_token.obj", "v 0 0 0\n" + std::string(1 << 20, 'q') + "\n");
    expect_refused(run_bad(p), "huge_token.obj:2: a token of 1048576 bytes is longer than the limit of 4096 bytes");
}

TEST_F(GeneratedScene, BinaryGarbage) {
    // A PNG header: the NUL bytes come after the second '\n', on line 3.
    const std::string p = write("garbage.obj", std::string("\x89PNG\r\n\x1a\n\0\0\0\rIHDR\xff\xfe", 18));
    expect_refused(run_bad(p), "garbage.obj:3: not an OBJ file (binary data: a NUL byte)");
}

TEST(BadSceneCliPaths, MissingFile) {
    const std::string p = (kBad / "does_not_exist.obj").string();
    expect_refused(run_bad(p), p + ": cannot read the scene: no such file");
}

TEST(BadSceneCliPaths, DirectoryAsScene) {
    expect_refused(run_bad(kBad.string()), kBad.string() + ": is a directory, not an OBJ file");
}

TEST(BadSceneCliMemory, TinyPatchEdgeIsRefusedUpFrontWithTheEstimate) {
    // The unit cube with edge 1e-5 makes 6 × 1e10 = 6e10 patches: about 6e10 × (patch + vertex)
    // bytes, far beyond any machine's memory. The refusal must name the estimate and come before
    // anything proportional to it is allocated: the process's peak resident memory stays that of
    // an idle ffcube (tens of MB; 256 MB leaves room for sanitizer runtimes), not gigabytes.
    TempDir dir;
    const std::string log = dir / "log.txt";
    const auto [code, maxrss_kib] =
        test::run_measured({"formfactors", test::example("cube.obj"), "--max-patch-edge", "1e-5", "-q", "-o", dir / "F.ffm",
                      "--groups", dir / "G.csv", "--report", dir / "R.json"},
                     log);
    const std::string out = test::read_text(log);
    EXPECT_EQ(code, 2) << out;
    EXPECT_NE(out.find("--max-patch-edge 1e-05 would make about 6e+10 patches (needs about"), std::string::npos) << out;
    EXPECT_NE(out.find("GB); the limit is"), std::string::npos) << out;
    EXPECT_LT(maxrss_kib, 256 * 1024);
    for (const char* name : {"F.ffm", "G.csv", "R.json"}) EXPECT_FALSE(fs::exists(dir / name)) << name;
}

}  // namespace
}  // namespace ffcube

namespace ffcube {
namespace {

// An error raised inside a hemicube worker process (test hook FFCUBE_TEST_WORKER_FAIL, see
// docs/robustness.md) exits with its class's code, as it would from a worker thread
// (tests/gl/test_worker_errors.cpp shows the classes agree), and leaves no output.
TEST(WorkerErrorsCli, ExitCodeFollowsTheClassRaisedInTheWorker) {
    const std::pair<const char*, int> cases[] = {{"input", 2}, {"io", 3}, {"gl", 4}, {"internal", 70}};
    for (const auto& [fail, code] : cases) {
        test::TempDir dir;
        const auto r = test::run_ffcube_env(std::string("FFCUBE_TEST_WORKER_FAIL=") + fail + " ",
                                            "formfactors " + test::example("cube.obj") +
                                                " --max-patch-edge 0.5 --resolution 16 --correct none --threads 2 -q -o " +
                                                (dir / "F.ffm"));
        EXPECT_EQ(r.code, code) << fail << ": " << r.output;
        EXPECT_NE(r.output.find("FFCUBE_TEST_WORKER_FAIL"), std::string::npos) << r.output;
        EXPECT_FALSE(std::filesystem::exists(dir / "F.ffm")) << fail;
    }
}

// A worker process killed from outside (FFCUBE_TEST_WORKER_FAIL=kill: it sends itself SIGKILL at
// its first row, as the OOM killer would) ends the run as an I/O error that says how the worker
// ended, whether the parent first notices it reading the reply or sending the next row (rows are
// pipelined), and leaves no output.
TEST(WorkerErrorsCli, AKilledWorkerIsAnIoErrorThatSaysSo) {
    for (const char* threads : {"1", "2"}) {
        test::TempDir dir;
        const auto r = test::run_ffcube_env("FFCUBE_TEST_WORKER_FAIL=kill ",
                                            "formfactors " + test::example("cube.obj") +
                                                " --max-patch-edge 0.5 --resolution 16 --correct none --threads " + threads + " -q -o " +
                                                (dir / "F.ffm"));
        EXPECT_EQ(r.code, 3) << r.output;
        EXPECT_NE(r.output.find("a hemicube worker process was killed by signal 9 unexpectedly"), std::string::npos)
            << r.output;
        EXPECT_FALSE(std::filesystem::exists(dir / "F.ffm"));
    }
}

}  // namespace
}  // namespace ffcube
