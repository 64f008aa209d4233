// The files other solvers read, parsed back by small readers written here from the formats'
// descriptions (View3D's savevf.c/readvf.c, Elmer's ViewFactors.F90), not from ffcube's writers.
#include <gtest/gtest.h>

#include <cstring>
#include <sstream>

#include "ffcube/io/solver_files.hpp"
#include "io/io_test_util.hpp"
#include "support/view3d_text.hpp"

namespace ffcube {
namespace {

using test::read_all;

class SolverFiles : public test::ScratchDir {};

using View3dFile = test::View3dText;

// readvf.c's ReadF1s: fread(header, 32), then float32 blocks.
View3dFile read_view3d_binary(const std::string& bytes) {
    View3dFile f;
    std::istringstream head(bytes.substr(0, 32));
    head >> f.program >> f.version >> f.format >> f.encl >> f.emit >> f.n;
    const std::size_t n = f.n;
    EXPECT_EQ(bytes.size(), 32 + 4 * (n + n * n + n));
    std::size_t at = 32;
    const auto next = [&] {
        float v;
        std::memcpy(&v, bytes.data() + at, 4);
        at += 4;
        return static_cast<double>(v);
    };
    for (std::size_t i = 0; i < n; ++i) f.area.push_back(next());
    f.F.assign(n, std::vector<double>(n));
    for (auto& row : f.F)
        for (auto& v : row) v = next();
    for (std::size_t i = 0; i < n; ++i) f.emissivity.push_back(next());
    return f;
}

View3dTable table() {
    View3dTable t;
    t.area = {1.0, 0.5, 12.25};
    t.F = {{0.0, 0.123456789, 0.5}, {0.25, 0.0, 1.0 / 3.0}, {0.01, 0.02, 0.0}};
    t.emissivity = {0.9, 0.85, 0.123};
    t.encl = 1;
    return t;
}

TEST_F(SolverFiles, View3dHeaderIsPaddedAsSaveVfWritesIt) {
    const std::string text = view3d_header(0, 1, 0, 3);
    EXPECT_EQ(text, "View3D 3.5 0 1 0 3" + std::string(30 - 18, ' ') + "\n");
    EXPECT_EQ(text.size(), 31u);  // savevf.c: 30 bytes, '\n', then the NUL that fprintf stops at
    const std::string binary = view3d_header(1, 0, 1, 1234567);
    ASSERT_EQ(binary.size(), 32u);
    EXPECT_EQ(binary.substr(0, 30), "View3D 3.5 1 0 1 1234567" + std::string(30 - 24, ' '));
    EXPECT_EQ(binary.substr(30), "\r\n");
}

TEST_F(SolverFiles, View3dTextRoundTrips) {
    const View3dTable t = table();
    write_view3d(path("vf.txt"), t, false);
    const std::string bytes = read_all(path("vf.txt"));
    EXPECT_EQ(bytes.substr(0, 31), view3d_header(0, 1, 0, 3));
    EXPECT_NE(bytes.find("\n1 0.5 12.25\n0.000000 0.123457 0.500000\n"), std::string::npos) << bytes;
    const View3dFile f = test::read_view3d(bytes);
    EXPECT_EQ(f.program, "View3D");
    EXPECT_EQ(f.format, 0);
    EXPECT_EQ(f.encl, 1);
    EXPECT_EQ(f.emit, 0);
    ASSERT_EQ(f.n, 3u);
    for (std::size_t i = 0; i < 3; ++i) {
        EXPECT_NEAR(f.area[i], t.area[i], 1e-6 * t.area[i]);  // %g: 6 significant digits
        EXPECT_NEAR(f.emissivity[i], t.emissivity[i], 5e-4);   // %.3f
        for (std::size_t j = 0; j < 3; ++j) EXPECT_NEAR(f.F[i][j], t.F[i][j], 5e-7);  // %.6f
    }
}

TEST_F(SolverFiles, View3dBinaryRoundTripsExactlyInFloat) {
    const View3dTable t = table();
    write_view3d(path("vf.bin"), t, true);
    const std::string bytes = read_all(path("vf.bin"));
    EXPECT_EQ(bytes.substr(0, 32), view3d_header(1, 1, 0, 3));
    const View3dFile f = read_view3d_binary(bytes);
    EXPECT_EQ(f.format, 1);
    ASSERT_EQ(f.n, 3u);
    for (std::size_t i = 0; i < 3; ++i) {
        EXPECT_EQ(f.area[i], static_cast<double>(static_cast<float>(t.area[i])));
        EXPECT_EQ(f.emissivity[i], static_cast<double>(static_cast<float>(t.emissivity[i])));
        for (std::size_t j = 0; j < 3; ++j) EXPECT_EQ(f.F[i][j], static_cast<double>(static_cast<float>(t.F[i][j])));
    }
}

TEST_F(SolverFiles, ElmerTextAndBinaryRoundTrip) {
    const CsrMatrix F = test::small_matrix();
    write_elmer_view_factors(path("vf.dat"), F, false);
    // Text: per row a count, then "i j F" lines (Fortran list-directed reads take any blanks).
    std::istringstream in(read_all(path("vf.dat")));
    for (std::uint32_t i = 0; i < F.size(); ++i) {
        const RowView r = F.row(i);
        std::size_t k = 99;
        ASSERT_TRUE(in >> k);
        ASSERT_EQ(k, r.col.size()) << "row " << i;
        for (std::size_t e = 0; e < k; ++e) {
            std::uint32_t ii = 0, jj = 0;
            double v = 0;
            ASSERT_TRUE(in >> ii >> jj >> v);
            EXPECT_EQ(ii, i + 1);
            EXPECT_EQ(jj, r.col[e] + 1);
            EXPECT_EQ(static_cast<float>(v), r.val[e]);  // 9 significant digits: exact in float
        }
    }
    std::string rest;
    EXPECT_FALSE(in >> rest);
    // Binary: int32 N, then per row int32 k and k × (int32 j, float64 F).
    write_elmer_view_factors(path("vf.bin"), F, true);
    const std::string b = read_all(path("vf.bin"));
    std::size_t at = 0;
    const auto i32 = [&] {
        std::int32_t v;
        std::memcpy(&v, b.data() + at, 4);
        at += 4;
        return v;
    };
    const auto f64 = [&] {
        double v;
        std::memcpy(&v, b.data() + at, 8);
        at += 8;
        return v;
    };
    ASSERT_EQ(i32(), 5);
    for (std::uint32_t i = 0; i < F.size(); ++i) {
        const RowView r = F.row(i);
        ASSERT_EQ(static_cast<std::size_t>(i32()), r.col.size());
        for (std::size_t e = 0; e < r.col.size(); ++e) {
            EXPECT_EQ(i32(), static_cast<std::int32_t>(r.col[e] + 1));
            EXPECT_EQ(f64(), static_cast<double>(r.val[e]));
        }
    }
    EXPECT_EQ(at, b.size());
}

TEST_F(SolverFiles, PatchTableAndSkyCsv) {
    Scene s = test::small_scene();
    s.patches[1].centroid = Vec3(0.5, -1.25, 3.0);
    s.patches[1].normal = Vec3(0.0, 0.0, -1.0);
    write_patch_table(path("p.csv"), s);
    const std::string table = read_all(path("p.csv"));
    EXPECT_EQ(table.rfind("patch,object,area,cx,cy,cz,nx,ny,nz\n0,floor,1,", 0), 0u) << table;
    EXPECT_NE(table.find("\n1,floor,0.5,0.5,-1.25,3,0,0,-1\n"), std::string::npos) << table;
    EXPECT_NE(table.find("\n2,\"light, ceiling\",0.25,"), std::string::npos);  // RFC 4180 quoting
    EXPECT_EQ(std::count(table.begin(), table.end(), '\n'), 6);
    write_patch_sky_csv(path("s.csv"), s, {0.5, 0.25, 1.0, 0.0, 0.125});
    EXPECT_NE(read_all(path("s.csv")).find("patch,object,area,sky_view_factor\n0,floor,1,0.5\n1,floor,0.5,0.25\n"),
              std::string::npos);
    write_object_sky_csv(path("o.csv"), s.objects, {1.5, 0.25, 2.125}, {0.4, 1.0, 0.0});
    EXPECT_EQ(read_all(path("o.csv")),
              "object,area,sky_view_factor\nfloor,1.5,0.4\n\"light, ceiling\",0.25,1\n\"wall \"\"A\"\"\",2.125,0\n");
}

}  // namespace
}  // namespace ffcube
