// Issue 43 through the binary: every hostile PLY/glTF/GLB class (tests/support/hostile_imports.hpp)
// given to `ffcube formfactors FILE -o F.ffm --report R.json` ends with exit 2, a message naming
// the file and the rule, and an empty output directory; FIFOs as the scene, as --materials, as
// `solve --matrix` and as a glTF buffer are refused at once instead of blocking. Every run is
// under `timeout 60`, so a hang fails the test (exit 124) instead of stalling the suite.
#include <gtest/gtest.h>

#include <sys/stat.h>

#include <filesystem>
#include <string>
#include <vector>

#include "cli/cli_util.hpp"
#include "support/hostile_imports.hpp"

namespace fs = std::filesystem;

namespace ffcube {
namespace {

using test::run_ffcube_env;
using test::TempDir;

struct Outcome {
    int code = -1;
    std::string output;
    std::vector<std::string> files_left;
};

Outcome run_in(const TempDir& out, const std::string& args) {
    const auto r = run_ffcube_env("timeout 60 ", args);
    Outcome o{r.code, r.output, {}};
    for (const auto& e : fs::directory_iterator(out.path())) o.files_left.push_back(e.path().filename().string());
    return o;
}

void expect_refused(const Outcome& o, const std::string& message) {
    EXPECT_EQ(o.code, 2) << o.output.substr(0, 500);
    EXPECT_NE(o.output.find(message), std::string::npos) << "expected: " << message << "\ngot: " << o.output.substr(0, 500);
    EXPECT_TRUE(o.files_left.empty()) << "left behind: " << o.files_left.front();
}

class HostileImportCli : public testing::TestWithParam<test::HostileFile> {};

TEST_P(HostileImportCli, RefusedWithTheRuleExit2AndNoOutput) {
    const test::HostileFile& f = GetParam();
    TempDir in, out;
    const fs::path scene = test::write_hostile(in.path(), f);
    expect_refused(run_in(out, "formfactors '" + scene.string() + "' -q --resolution 16 -o " + (out / "F.ffm") + " --report " +
                                   (out / "R.json")),
                   f.message);
}

INSTANTIATE_TEST_SUITE_P(Issue43, HostileImportCli, testing::ValuesIn(test::hostile_files()),
                         [](const testing::TestParamInfo<test::HostileFile>& case_info) {
                             std::string name = case_info.param.name;
                             for (char& c : name)
                                 if (!std::isalnum(static_cast<unsigned char>(c))) c = '_';
                             return name;
                         });

TEST(FifoInputsCli, AFifoSceneIsRefusedAtOnce) {
    TempDir in, out;
    for (const char* name : {"pipe.obj", "pipe.ply", "pipe.stl", "pipe.vs3", "pipe.gltf"}) {
        SCOPED_TRACE(name);
        ASSERT_EQ(::mkfifo((in / name).c_str(), 0600), 0);
        expect_refused(run_in(out, "formfactors " + (in / name) + " -q -o " + (out / "F.ffm")),
                       in / name + ": is a FIFO (named pipe), not");
    }
}

TEST(FifoInputsCli, AFifoMaterialsFileIsRefusedAtOnce) {
    TempDir in, out;
    ASSERT_EQ(::mkfifo((in / "m.csv").c_str(), 0600), 0);
    expect_refused(run_in(out, "formfactors " + test::example("cube.obj") + " -q --resolution 16 --materials " + (in / "m.csv") +
                                   " -o " + (out / "F.ffm")),
                   in / "m.csv" + ": is a FIFO (named pipe), not a materials CSV file");
}

TEST(FifoInputsCli, SolveWithAFifoMatrixIsRefusedAtOnce) {
    // It used to block in open() for ever, waiting for a writer.
    TempDir in, out;
    ASSERT_EQ(::mkfifo((in / "F.ffm").c_str(), 0600), 0);
    expect_refused(run_in(out, "solve " + test::example("cube.obj") + " -q --matrix " + (in / "F.ffm") + " --radiosity " +
                                   (out / "B.csv")),
                   in / "F.ffm" + ": is a FIFO (named pipe), not a matrix file");
    // A directory and a device, the same way.
    expect_refused(run_in(out, "solve " + test::example("cube.obj") + " -q --matrix " + in.path().string() + " --radiosity " +
                                   (out / "B.csv")),
                   in.path().string() + ": is a directory, not a matrix file");
    expect_refused(run_in(out, "solve " + test::example("cube.obj") + " -q --matrix /dev/zero --radiosity " + (out / "B.csv")),
                   "/dev/zero: is a character device, not a matrix file");
}

}  // namespace
}  // namespace ffcube
