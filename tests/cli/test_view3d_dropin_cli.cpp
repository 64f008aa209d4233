// `ffcube view3d IN OUT` and `ffcube-view3d IN OUT`, the View3D drop-in (docs/urban.md): the
// forks' sparse text (out=2) read line by line against the text file and the Matrix Market file of
// `ffcube formfactors --no-subdivide --enforce reciprocity` (View3D's factors are reciprocal by
// construction, and so are the drop-in's) on the same file, out=0/1 byte for byte as --view3d writes
// them, the two executables' bytes alike, maxD, and the control keys refused with the line.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <functional>
#include <map>
#include <regex>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

#include "cli/cli_util.hpp"
#include "support/view3d_text.hpp"

namespace ffcube {
namespace {

using test::kView3dCubeVertices;
using test::kView3dOpenBoxSurfaces;
using test::read_text;
using test::read_view3d;
using test::run_ffcube;
using test::TempDir;
using test::View3dText;
using test::write_file;

// ffcube-view3d is built beside ffcube.
std::string view3d_exe() { return (std::filesystem::path(FFCUBE_BINARY).parent_path() / "ffcube-view3d").string(); }

test::RunResult run_exe(const std::string& exe, const std::string& args) {
    const std::string cmd = exe + " " + args + " 2>&1";
    test::RunResult r;
    FILE* p = popen(cmd.c_str(), "r");
    if (!p) return r;
    char buf[4096];
    std::size_t n;
    while ((n = std::fread(buf, 1, sizeof buf, p)) > 0) r.output.append(buf, n);
    const int status = pclose(p);
    r.code = WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
    return r;
}

using Entries = std::map<std::pair<int, int>, double>;

// The out=2 file as the forks write it (savevf.c SaveF2: "%d %d %.6f\n" for F >= 5e-7), checked
// line by line: 1 <= i, j <= n, six decimals, rows in order and columns increasing in each.
Entries read_sparse(const std::string& bytes, int n) {
    Entries e;
    static const std::regex line_rx(R"(([1-9][0-9]*) ([1-9][0-9]*) ([0-9]+\.[0-9]{6}))");
    std::istringstream in(bytes);
    std::string line;
    int last_i = 0, last_j = 0, number = 0;
    while (std::getline(in, line)) {
        ++number;
        std::smatch m;
        EXPECT_TRUE(std::regex_match(line, m, line_rx)) << "line " << number << ": '" << line << "'";
        if (m.empty()) continue;
        const int i = std::stoi(m[1]), j = std::stoi(m[2]);
        const double f = std::stod(m[3]);
        EXPECT_TRUE(i >= 1 && i <= n && j >= 1 && j <= n) << line;
        EXPECT_TRUE(i > last_i || (i == last_i && j > last_j)) << "out of order: " << line;
        EXPECT_GT(f, 0.0) << line;  // >= 5e-7 prints as at least 0.000001
        EXPECT_LE(f, 1.0) << line;
        last_i = i, last_j = j;
        e[{i, j}] = f;
    }
    EXPECT_TRUE(bytes.empty() || bytes.back() == '\n');
    return e;
}

// Matrix Market entries (1-based).
Entries read_mtx(const std::string& bytes) {
    Entries e;
    std::istringstream in(bytes);
    std::string line;
    while (std::getline(in, line) && line[0] == '%') {
    }
    int i, j;
    double v;
    while (in >> i >> j >> v) e[{i, j}] = v;
    return e;
}

// Every entry of `sparse` within `tol` of the dense or listed value, and every value of at least
// 1e-6 present in `sparse` (smaller ones may print as 0.000000 or 0.000001 and so be left out).
void expect_same_entries(const Entries& sparse, const std::function<double(int, int)>& value, int n, double tol) {
    int listed = 0;
    for (int i = 1; i <= n; ++i)
        for (int j = 1; j <= n; ++j) {
            const double v = value(i, j);
            const auto it = sparse.find({i, j});
            if (it == sparse.end()) {
                EXPECT_LT(v, 1e-6) << "missing " << i << " " << j;
                continue;
            }
            ++listed;
            EXPECT_NEAR(it->second, v, tol) << i << " " << j;
        }
    EXPECT_EQ(listed, static_cast<int>(sparse.size()));  // nothing outside 1..n
}

std::string open_box(const std::string& control) {
    return "T open unit box\r\nC " + control + "\r\n" + kView3dCubeVertices + kView3dOpenBoxSurfaces + "End of Data\r\n";
}

TEST(View3dDropInCli, SparseOutputOfTheOpenBoxIsTheTextOutputsEntries) {
    TempDir dir;
    write_file(dir / "box.vs3", open_box("encl=0 emit=0 out=2"));  // CRLF lines, as uDALES writes them
    auto r = run_ffcube("view3d " + (dir / "box.vs3") + " " + (dir / "sparse.txt"));
    ASSERT_EQ(r.code, 0) << r.output;
    // The same file through formfactors, reciprocal as View3D's factors (what `ffcube view3d`
    // does): --view3d in text, and in the file's own out=2.
    r = run_ffcube("formfactors " + (dir / "box.vs3") + " --no-subdivide -q --enforce reciprocity --view3d " +
                   (dir / "text.txt") + " --view3d-format text");
    ASSERT_EQ(r.code, 0) << r.output;
    r = run_ffcube("formfactors " + (dir / "box.vs3") + " --no-subdivide -q --enforce reciprocity --view3d " +
                   (dir / "ff_sparse.txt"));
    ASSERT_EQ(r.code, 0) << r.output;
    const std::string sparse = read_text(dir / "sparse.txt");
    const View3dText text = read_view3d(read_text(dir / "text.txt"));
    ASSERT_EQ(text.n, 5u);
    const Entries e = read_sparse(sparse, 5);
    // Each wall sees the floor and three walls, the floor four walls: 4 × 5 entries.
    EXPECT_EQ(e.size(), 20u);
    // %.6f of the double against %.6f of its float: one unit of the sixth decimal apart at most.
    expect_same_entries(e, [&](int i, int j) { return text.F[i - 1][j - 1]; }, 5, 1.0000001e-6);
    // formfactors --view3d with the file's out=2 (the dense table) writes the same bytes as
    // `ffcube view3d` (the rows summed straight from F).
    EXPECT_EQ(read_text(dir / "ff_sparse.txt"), sparse);
    // ffcube-view3d, View3D's two arguments: the same bytes.
    r = run_exe(view3d_exe(), (dir / "box.vs3") + " " + (dir / "exe.txt"));
    ASSERT_EQ(r.code, 0) << r.output;
    EXPECT_EQ(read_text(dir / "exe.txt"), sparse);
}

TEST(View3dDropInCli, TextAndBinaryAreWhatFormfactorsWrites) {
    TempDir dir;
    for (const int out : {0, 1}) {
        const std::string in = dir / ("box" + std::to_string(out) + ".vs3");
        write_file(in, open_box("out=" + std::to_string(out)));
        auto r = run_ffcube("view3d -q " + in + " " + (dir / "a.out"));
        ASSERT_EQ(r.code, 0) << r.output;
        r = run_ffcube("formfactors " + in + " --no-subdivide -q --enforce reciprocity --view3d " + (dir / "b.out"));
        ASSERT_EQ(r.code, 0) << r.output;
        const std::string a = read_text(dir / "a.out");
        EXPECT_EQ(a, read_text(dir / "b.out")) << "out=" << out;
        EXPECT_EQ(a.rfind(out == 1 ? "View3D 3.5 1 0 0 5" : "View3D 3.5 0 0 0 5", 0), 0u) << a.substr(0, 32);
        if (out == 1) {
            EXPECT_EQ(a.size(), 32u + 4u * (5 + 25 + 5));
        }
    }
}

TEST(View3dDropInCli, BlocksCitySparseMatchesTheMatrixMarketRows) {
    // tools/gen_vs3_blocks.py: 508 quads (3 × 3 buildings, 5 m cells), every surface one row.
    TempDir dir;
    const std::string vs3 = dir / "blocks.vs3";
    ASSERT_EQ(std::system(("python3 " + std::string(FFCUBE_SOURCE_DIR) + "/tools/gen_vs3_blocks.py --cell 5 -o " + vs3 +
                           " > /dev/null")
                              .c_str()),
              0);
    std::string text = read_text(vs3);
    const std::size_t c = text.find("C encl=0 emit=0");
    ASSERT_NE(c, std::string::npos);
    text.replace(c, 15, "C encl=0 emit=0 out=2 row=0 col=0");  // as uDALES' stl_to_view3d writes it
    write_file(vs3, text);
    auto r = run_exe(view3d_exe(), vs3 + " " + (dir / "vf.txt"));
    ASSERT_EQ(r.code, 0) << r.output;
    r = run_ffcube("formfactors " + vs3 + " --no-subdivide -q --enforce reciprocity -o " + (dir / "F.mtx"));
    ASSERT_EQ(r.code, 0) << r.output;
    const Entries sparse = read_sparse(read_text(dir / "vf.txt"), 508);
    const Entries mtx = read_mtx(read_text(dir / "F.mtx"));
    // Every surface is one patch: the object rows are the patch rows. %.6f (5e-7) and the .mtx's
    // 9 digits apart.
    expect_same_entries(
        sparse,
        [&](int i, int j) {
            const auto it = mtx.find({i, j});
            return it == mtx.end() ? 0.0 : it->second;
        },
        508, 5e-7 + 1e-8);
    EXPECT_GT(sparse.size(), 10000u);  // a city's rows see many surfaces
    // `ffcube view3d` gives ffcube-view3d's bytes.
    r = run_ffcube("view3d -q " + vs3 + " " + (dir / "vf2.txt"));
    ASSERT_EQ(r.code, 0) << r.output;
    EXPECT_EQ(read_text(dir / "vf2.txt"), read_text(dir / "vf.txt"));
}

TEST(View3dDropInCli, MaxDLeavesOutPairsWhoseCentroidsLieFartherApart) {
    TempDir dir;
    // Centroids: adjacent faces 0.707 apart, opposite walls 1 apart. maxD=0.8 keeps the first.
    write_file(dir / "box.vs3", open_box("out=2 maxD=0.8"));
    auto r = run_ffcube("view3d " + (dir / "box.vs3") + " " + (dir / "vf.txt"));
    ASSERT_EQ(r.code, 0) << r.output;
    EXPECT_NE(r.output.find("box.vs3:2: maxD=0.8"), std::string::npos) << r.output;
    const Entries e = read_sparse(read_text(dir / "vf.txt"), 5);
    EXPECT_EQ(e.size(), 16u);  // 20 less south-north, north-south, west-east, east-west
    EXPECT_EQ(e.count({2, 3}) + e.count({3, 2}) + e.count({4, 5}) + e.count({5, 4}), 0u);
    EXPECT_EQ(e.count({1, 2}) + e.count({2, 4}), 2u);
    // formfactors computes every pair and says so, naming the line.
    r = run_ffcube("formfactors " + (dir / "box.vs3") + " --no-subdivide -q --view3d " + (dir / "ff.txt"));
    ASSERT_EQ(r.code, 0) << r.output;
    EXPECT_NE(r.output.find("box.vs3:2: control maxD=0.8 is ignored"), std::string::npos) << r.output;
    EXPECT_EQ(read_sparse(read_text(dir / "ff.txt"), 5).size(), 20u);
}

TEST(View3dDropInCli, BadControlKeysAreRefusedWithTheLineAndNoOutput) {
    TempDir dir;
    const std::vector<std::pair<std::string, std::string>> cases = {
        {"out=3", "box.vs3:2: control out=3 must be 0, 1 or 2"},
        {"encl=2", "box.vs3:2: control encl=2 must be 0 or 1"},
        {"row=3", "box.vs3:2: control row=3: View3D's one-row debugging run is not supported by ffcube view3d"},
        {"row=3 col=2", "box.vs3:2: control row=3: View3D's one-row"},
        {"col=2", "box.vs3:2: control col=2 needs row"},
        {"row=1.5", "box.vs3:2: control row=1.5 must be a surface number"},
        {"maxD=0", "box.vs3:2: control maxD=0 must be > 0"},
        {"out=2 maxD=-5", "box.vs3:2: control maxD=-5 must be > 0"},
    };
    for (const auto& [control, message] : cases) {
        write_file(dir / "box.vs3", open_box(control));
        for (const std::string& exe : {std::string(FFCUBE_BINARY) + " view3d", view3d_exe()}) {
            const auto r = run_exe(exe, (dir / "box.vs3") + " " + (dir / "vf.txt"));
            EXPECT_EQ(r.code, 2) << control << ": " << r.output;
            EXPECT_NE(r.output.find(message), std::string::npos) << control << ": " << r.output;
            EXPECT_FALSE(std::filesystem::exists(dir / "vf.txt")) << control;
        }
    }
    // View3D's argument count, a missing input, an output in a missing directory: exit 2.
    EXPECT_EQ(run_exe(view3d_exe(), dir / "box.vs3").code, 2);
    EXPECT_EQ(run_exe(view3d_exe(), (dir / "none.vs3") + " " + (dir / "vf.txt")).code, 2);
    write_file(dir / "box.vs3", open_box("out=2"));
    const auto r = run_exe(view3d_exe(), (dir / "box.vs3") + " " + (dir / "no/vf.txt"));
    EXPECT_EQ(r.code, 2) << r.output;
    EXPECT_NE(r.output.find("OUT"), std::string::npos) << r.output;
}

TEST(View3dDropInCli, HelpIsShort) {
    const auto r = run_exe(view3d_exe(), "--help");
    EXPECT_EQ(r.code, 0) << r.output;
    EXPECT_NE(r.output.find("IN"), std::string::npos) << r.output;
    EXPECT_NE(r.output.find("OUT"), std::string::npos) << r.output;
    EXPECT_LT(std::count(r.output.begin(), r.output.end(), '\n'), 20) << r.output;
}

}  // namespace
}  // namespace ffcube
