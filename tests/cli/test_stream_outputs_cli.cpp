// The outputs other tools read (.mtx, Elmer's ViewFactors.dat, View3D's file) written from the row
// stream (io/matrix_sink.hpp) hold the same bytes at any --stats-memory (one band or several) and
// with or without a matrix file (the rows as computed held on disk or in memory), after each
// --enforce mode; the .mtx read back has the report's entries and row sums; nothing is left behind.
#include <fmt/format.h>
#include <gtest/gtest.h>

#include <nlohmann/json.hpp>
#include <algorithm>
#include <sstream>
#include <vector>

#include "cli/cli_util.hpp"

namespace ffcube {
namespace {

struct Case {
    std::string enforce, output_ext, formats;
    std::vector<std::string> memories;  // --stats-memory MiB of the runs compared with the default (512)
};

TEST(StreamOutputsCli, OutputsDoNotDependOnTheBudgetOrTheMatrixFile) {
    test::TempDir dir;
    // 768 patches: about 4.5e5 entries. The reciprocity check holds the columns' parts below the
    // diagonal (about 2.3e5 entries) and --enforce whole columns: either is more than the 131,072
    // a 1 MiB band holds (8 bytes each), so --stats-memory 1 makes several bands and 512 one. The
    // cube is closed: closure applies.
    const std::string scene = test::example("closed_cube.stl") + " --max-patch-edge 0.2 --resolution 32 -q";
    const std::vector<Case> cases = {
        {"", "mtx", "", {"1"}},
        {" --enforce closure", "mtx", " --elmer-format binary --view3d-format binary", {"1"}},
        {" --enforce reciprocity", "ffm", "", {"1"}},
    };
    const auto json = [&](const std::string& name) { return nlohmann::json::parse(test::read_text(dir / name)); };
    for (const Case& c : cases) {
        SCOPED_TRACE(c.enforce);
        const auto outputs = [&](const std::string& tag) {
            return fmt::format("-o {} --elmer {} --view3d {} --report {}{}", dir / (tag + "." + c.output_ext),
                               dir / (tag + ".dat"), dir / (tag + ".vf"), dir / (tag + ".json"), c.formats);
        };
        const auto m = test::run_ffcube(fmt::format("formfactors {}{} {}", scene, c.enforce, outputs("m")));
        ASSERT_EQ(m.code, 0) << m.output;
        const auto a = json("m.json");
        EXPECT_EQ(a[c.enforce.empty() ? "reciprocity" : "enforce"]["bands"].get<int>() > 1, false) << a.dump();
        // No matrix file: Elmer's and View3D's files are the same bytes.
        const auto w = test::run_ffcube(fmt::format("formfactors {}{} --elmer {} --view3d {}{}", scene, c.enforce,
                                                    dir / "w.dat", dir / "w.vf", c.formats));
        ASSERT_EQ(w.code, 0) << w.output;
        for (const char* ext : {".dat", ".vf"})
            EXPECT_TRUE(test::read_text(dir / ("w" + std::string(ext))) == test::read_text(dir / ("m" + std::string(ext))))
                << ext << " differs without a matrix file";
        for (const std::string& memory : c.memories) {
            SCOPED_TRACE(memory);
            const auto s = test::run_ffcube(
                fmt::format("formfactors {}{} --stats-memory {} {}", scene, c.enforce, memory, outputs("s")));
            ASSERT_EQ(s.code, 0) << s.output;
            const auto b = json("s.json");
            const char* passes_key = c.enforce.empty() ? "reciprocity" : "enforce";
            EXPECT_EQ(b[passes_key]["bands"].get<int>() > 1, memory == "1") << b.dump();
            for (const char* ext : {".dat", ".vf", ".json"}) {
                if (std::string(ext) == ".json") {
                    for (const char* k : {"nnz", "row_sums", "sky"}) EXPECT_EQ(a[k], b[k]) << k;
                    for (const char* k : {"patch_max_abs", "object_max_rel"})
                        EXPECT_EQ(a["reciprocity"][k], b["reciprocity"][k]) << k;
                    continue;
                }
                const std::string mb = test::read_text(dir / ("m" + std::string(ext)));
                EXPECT_GT(mb.size(), 0u) << ext;
                EXPECT_TRUE(mb == test::read_text(dir / ("s" + std::string(ext)))) << ext << " differs";
            }
            const std::string mo = test::read_text(dir / ("m." + c.output_ext));
            EXPECT_TRUE(mo == test::read_text(dir / ("s." + c.output_ext))) << c.output_ext << " differs";
            if (c.output_ext == "mtx") {
                // The header's count (known only after the last row) is the number of entry lines.
                std::istringstream in(mo);
                std::string line;
                std::getline(in, line);
                std::getline(in, line);
                std::uint64_t rows = 0, cols = 0, nnz = 0, lines = 0;
                in >> rows >> cols >> nnz;
                std::getline(in, line);
                // Each entry "i j v" (1-based), rows in order; v printed to 9 significant digits,
                // which gives the float back exactly: row sums in double, added in column order as
                // RowView::sum adds them, are the report's to the last bit.
                std::vector<double> sums(rows, 0.0);
                std::uint64_t i = 0, j = 0;
                float v = 0;
                while (std::getline(in, line)) {
                    ++lines;
                    std::istringstream(line) >> i >> j >> v;
                    sums.at(i - 1) += static_cast<double>(v);
                }
                EXPECT_EQ(rows, 768u);
                EXPECT_EQ(nnz, lines);
                EXPECT_EQ(*std::min_element(sums.begin(), sums.end()), b["row_sums"]["min"].get<double>());
                EXPECT_EQ(*std::max_element(sums.begin(), sums.end()), b["row_sums"]["max"].get<double>());
                EXPECT_EQ(static_cast<double>(nnz), b["nnz"].get<double>());
            }
        }
    }
    for (const auto& entry : std::filesystem::directory_iterator(dir.path()))
        EXPECT_NE(entry.path().filename().string().front(), '.') << "left behind: " << entry.path();
}

}  // namespace
}  // namespace ffcube
