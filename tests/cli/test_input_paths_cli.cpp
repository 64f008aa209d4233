// No file outside the model is read, and no input path can block (issue 43): an OBJ's mtllib that
// is absolute or leaves the OBJ's folder is refused naming it, and --cost-model takes regular
// files only (a FIFO is refused at once instead of blocking the read).
#include <gtest/gtest.h>
#include <sys/stat.h>

#include <filesystem>
#include <string>

#include "cli/cli_util.hpp"

namespace ffcube {
namespace {

using test::TempDir;

const char* kSquare = "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf 1 2 3 4\n";

TEST(InputPathsCli, MtllibOutsideTheModelsFolderIsRefused) {
    TempDir dir;
    std::filesystem::create_directories(dir / "model");
    test::write_file(dir / "outside.mtl", "newmtl red\nKd 0.9 0.1 0.1\n");
    test::write_file(dir / "model/inside.mtl", "newmtl red\nKd 0.9 0.1 0.1\n");
    const std::string out = dir / "F.ffm";
    struct Case {
        std::string mtllib, message;
    };
    for (const Case& c : {Case{"../outside.mtl", "outside the model's folder"}, Case{dir / "outside.mtl", "an absolute path"},
                          Case{"/etc/passwd", "an absolute path"}}) {
        test::write_file(dir / "model/s.obj", "mtllib " + c.mtllib + "\nusemtl red\n" + kSquare);
        // `timeout 60`: a read that blocked would fail the test instead of stalling the suite.
        const auto r = test::run_ffcube_env("timeout 60 ", "formfactors " + (dir / "model/s.obj") + " -q -o " + out);
        EXPECT_EQ(r.code, 2) << c.mtllib << "\n" << r.output;
        EXPECT_NE(r.output.find("mtllib '" + c.mtllib + "'"), std::string::npos) << r.output;
        EXPECT_NE(r.output.find(c.message), std::string::npos) << r.output;
        EXPECT_FALSE(std::filesystem::exists(out));
    }
    // Inside the folder (also through a subfolder path that stays inside) it is read as before.
    test::write_file(dir / "model/s.obj", "mtllib ./inside.mtl\nusemtl red\n" + std::string(kSquare));
    const auto ok = test::run_ffcube("formfactors " + (dir / "model/s.obj") + " -q -o " + out);
    EXPECT_EQ(ok.code, 0) << ok.output;
    EXPECT_EQ(ok.output.find("not found"), std::string::npos) << ok.output;
}

TEST(InputPathsCli, CostModelMustBeARegularFile) {
    TempDir dir;
    const std::string fifo = dir / "costs.json";
    ASSERT_EQ(::mkfifo(fifo.c_str(), 0600), 0);
    const auto r = test::run_ffcube_env("timeout 60 ", "formfactors " + test::example("parallel_squares.obj") +
                                                           " -q --set cost-model=" + fifo + " -o " + (dir / "F.ffm"));
    EXPECT_EQ(r.code, 2) << r.output;
    EXPECT_NE(r.output.find("--cost-model " + fifo + ": is a FIFO"), std::string::npos) << r.output;
    EXPECT_FALSE(std::filesystem::exists(dir / "F.ffm"));
}

}  // namespace
}  // namespace ffcube
