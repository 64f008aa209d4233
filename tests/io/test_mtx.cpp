#include <fmt/format.h>
#include <gtest/gtest.h>

#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <sstream>
#include <string>

#include "ffcube/core/error.hpp"
#include "ffcube/io/mtx.hpp"
#include "io/io_test_util.hpp"

namespace ffcube::test {
namespace {

using Mtx = ScratchDir;

TEST_F(Mtx, RoundTripIsExact) {
    const CsrMatrix F = small_matrix();
    write_mtx(path("F.mtx"), F);
    std::istringstream in(read_all(path("F.mtx")));
    std::string line;
    std::getline(in, line);
    EXPECT_EQ(line, "%%MatrixMarket matrix coordinate real general");
    std::getline(in, line);
    EXPECT_EQ(line[0], '%');
    std::getline(in, line);
    EXPECT_EQ(line, "5 5 10");

    // Parse the entries back as a reader would and rebuild the matrix.
    CsrMatrix back(5);
    SparseRow row;
    std::uint32_t current = 0, entries = 0;
    while (std::getline(in, line)) {
        std::uint32_t i = 0, j = 0;
        char value[64] = {};
        ASSERT_EQ(std::sscanf(line.c_str(), "%u %u %63s", &i, &j, value), 3) << line;
        ASSERT_GE(i, 1u);
        ASSERT_GE(j, 1u);
        while (current < i - 1) {  // rows before i are complete (entries are in row order)
            back.append_row(row);
            row.clear();
            ++current;
        }
        ASSERT_EQ(current, i - 1) << "rows out of order at " << line;
        // strtof of the 9-digit text must give back the very same float.
        row.col.push_back(j - 1);
        row.val.push_back(std::strtof(value, nullptr));
        ++entries;
    }
    while (current < 5) {
        back.append_row(row);
        row.clear();
        ++current;
    }
    EXPECT_EQ(entries, 10u);
    EXPECT_EQ(back.row_ptr(), F.row_ptr());
    EXPECT_EQ(back.col(), F.col());
    for (std::size_t k = 0; k < F.val().size(); ++k)
        EXPECT_EQ(std::memcmp(&back.val()[k], &F.val()[k], sizeof(float)), 0) << k << ": " << back.val()[k];
}

TEST_F(Mtx, NineDigitsAreNeededAndWritten) {
    // 1/3 as a float is 0.333333343267...; 8 digits ("0.33333334") would read back as the same
    // float here, but the contract is %.9g for every value: check the text itself.
    CsrMatrix F(2);
    const std::vector<std::uint32_t> c = {1};
    const std::vector<float> v = {1.0f / 3.0f};
    F.append_row(c, v);
    F.append_row(SparseRow{});
    write_mtx(path("F.mtx"), F);
    const std::string text = read_all(path("F.mtx"));
    EXPECT_NE(text.find("\n2 2 1\n1 2 0.333333343\n"), std::string::npos) << text;
}

// Rows fed one at a time: the header's count is only known at finish(), when the file appears
// (with the bytes write_mtx gives for the same matrix); the spooled entry lines have no name, so a
// writer given up before finish() leaves nothing at all in the directory.
TEST_F(Mtx, StreamedWriterAppearsOnlyAtFinishAndLeavesNothingWhenAbandoned) {
    const CsrMatrix F = small_matrix();
    write_mtx(path("whole.mtx"), F);
    {
        MtxWriter w(path("F.mtx"), F.size());
        for (std::uint32_t i = 0; i < F.size(); ++i) w.append_row(F.row(i));
        EXPECT_FALSE(std::filesystem::exists(path("F.mtx")));
        EXPECT_EQ(w.nnz(), F.nnz());
        w.finish();
    }
    EXPECT_EQ(read_all(path("F.mtx")), read_all(path("whole.mtx")));
    {
        MtxWriter w(path("G.mtx"), F.size());
        w.append_row(F.row(0));
    }
    EXPECT_EQ(entries().size(), 2u);  // whole.mtx and F.mtx only
    // A directory that does not exist fails when the writer is made, before any row.
    EXPECT_THROW(MtxWriter(path("missing") / "F.mtx", 5), IoError);
}

std::string python_with_scipy() {
    for (const char* py : {"python3", "/usr/bin/python3"}) {
        const std::string cmd = std::string(py) + " -c 'import scipy.io' >/dev/null 2>&1";
        if (std::system(cmd.c_str()) == 0) return py;
    }
    return "";
}

TEST_F(Mtx, ScipyMmreadReadsIt) {
    const std::string py = python_with_scipy();
    if (py.empty()) GTEST_SKIP() << "no python3 with scipy";
    const CsrMatrix F = small_matrix();
    write_mtx(path("F.mtx"), F);
    const std::string cmd = py +
                            " -c 'import sys, scipy.io; m = scipy.io.mmread(sys.argv[1]).tocsr(); m.sort_indices();"
                            " print(m.shape, m.nnz, m.indptr.tolist(), m.indices.tolist(),"
                            " \" \".join(\"%.9g\" % v for v in m.data))' '" +
                            path("F.mtx").string() + "' 2>&1";
    std::string out;
    FILE* p = ::popen(cmd.c_str(), "r");
    ASSERT_NE(p, nullptr);
    char buf[4096];
    std::size_t got;
    while ((got = std::fread(buf, 1, sizeof buf, p)) > 0) out.append(buf, got);
    ::pclose(p);

    std::string values;
    for (float v : F.val()) values += (values.empty() ? "" : " ") + fmt::format("{:.9g}", static_cast<double>(v));
    // mmread gives float64 values of the 9-digit text; printed again with 9 digits they are that text.
    EXPECT_EQ(out, "(5, 5) 10 [0, 3, 5, 9, 9, 10] [1, 2, 4, 0, 3, 0, 1, 3, 4, 2] " + values + "\n");
}

}  // namespace
}  // namespace ffcube::test
