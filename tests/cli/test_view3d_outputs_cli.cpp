// The outputs other tools read, through the real binary (docs/outputs.md): sky view factors
// against closed forms and the ray caster, View3D's file with cmb combination against a closed
// form, the .vs3 control keys encl/emit/out, Elmer's ViewFactors.dat and the patch table against
// the .mtx of the same run.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <fstream>
#include <map>
#include <nlohmann/json.hpp>
#include <sstream>
#include <vector>

#include "cli/cli_util.hpp"
#include "support/view3d_text.hpp"
#include "ffcube/reference/closed_forms.hpp"
#include "ffcube/geometry/analytic.hpp"

namespace ffcube {
namespace {

using test::read_text;
using test::run_ffcube;
using test::TempDir;
using test::kView3dCubeVertices;
using test::kView3dOpenBoxSurfaces;
using test::last_column_by_first;
using test::read_view3d;
using test::View3dText;
using test::write_file;

TEST(SkyCli, OpenBoxMatchesClosedFormsAndTheRayCaster) {
    TempDir dir;
    write_file(dir / "box.vs3", std::string("T open unit box\n") + kView3dCubeVertices + kView3dOpenBoxSurfaces + "End\n");
    // Sky view factor of the floor = its factor to the opening, a parallel unit square at distance
    // 1 (Howell C-11); of a wall = its factor to the opening, a square sharing an edge (C-14).
    const double floor_exact = ff_parallel_rectangles(1.0, 1.0, 1.0);                  // 0.19982
    const double wall_exact = ff_perpendicular_rectangles_common_edge(1.0, 1.0, 1.0);  // 0.20004
    auto r = run_ffcube("formfactors " + (dir / "box.vs3") + " --no-subdivide -q --sky " + (dir / "sky.csv") +
                        " --sky-by object --report " + (dir / "r.json"));
    ASSERT_EQ(r.code, 0) << r.output;
    auto sky = last_column_by_first(read_text(dir / "sky.csv"));
    ASSERT_EQ(sky.size(), 5u);
    // Every pair of faces of the open box is near (centroids within 3 patch sizes) and unoccluded
    // (a convex cavity), so the default correction gives exact area-to-area values; what is left
    // is float storage of 4 entries per row (4 × 2^-24 relative) and the 9 digits of the CSV.
    EXPECT_NEAR(sky["floor"], floor_exact, 1e-6);
    for (const char* wall : {"south", "north", "west", "east"}) EXPECT_NEAR(sky[wall], wall_exact, 1e-6) << wall;
    const auto report = nlohmann::json::parse(read_text(dir / "r.json"));
    EXPECT_NEAR(report["sky"]["min"].get<double>(), floor_exact, 1e-6);
    EXPECT_NEAR(report["sky"]["max"].get<double>(), wall_exact, 1e-6);
    EXPECT_NEAR(report["sky"]["mean"].get<double>(), (floor_exact + 4 * wall_exact) / 5, 1e-6);

    // Meshed (80 patches), per patch: the ray caster, an independent method, agrees with the
    // hemicube. A ray-cast SVF is a mean of N Bernoulli draws: standard error at most
    // 0.5/sqrt(N) = 1.1e-3 at N = 200000 (stratification only lowers it); 5 sigma, 5.6e-3, bounds
    // every one of the 80 patches with probability > 1 - 80 × 6e-7. The hemicube's own error is
    // far below that (the near and far values of a convex cavity are exact).
    r = run_ffcube("formfactors " + (dir / "box.vs3") + " --max-patch-edge 0.25 -q --sky " + (dir / "h.csv"));
    ASSERT_EQ(r.code, 0) << r.output;
    r = run_ffcube("formfactors " + (dir / "box.vs3") + " --max-patch-edge 0.25 -q --method raycast --rays 200000 --sky " +
                   (dir / "rc.csv"));
    ASSERT_EQ(r.code, 0) << r.output;
    const auto h = last_column_by_first(read_text(dir / "h.csv")), rc = last_column_by_first(read_text(dir / "rc.csv"));
    ASSERT_EQ(h.size(), 80u);
    ASSERT_EQ(rc.size(), 80u);
    double worst = 0.0;
    for (const auto& [patch, v] : h) worst = std::max(worst, std::abs(v - rc.at(patch)));
    std::printf("open box, 80 patches: max |SVF hemicube - SVF raycast| = %.2e\n", worst);
    EXPECT_LT(worst, 5.6e-3);
}

TEST(View3dCli, CombinedHalvesOfAPlateGiveTheWholePlatesFactor) {
    TempDir dir;
    // A unit plate made of two halves (surface 2 combined with surface 1: cmb = 1) facing a unit
    // square at distance 1. Combined, the plate's factor to the square is Howell C-11's 0.19982,
    // and the square's factor to the plate the same (equal areas).
    write_file(dir / "halves.vs3", R"(T halves
F 3
V 1 0 0 0
V 2 0.5 0 0
V 3 0.5 1 0
V 4 0 1 0
V 5 1 0 0
V 6 1 1 0
V 7 0 0 1
V 8 1 0 1
V 9 1 1 1
V 10 0 1 1
S 1 1 2 3 4 0 0 0.9 plate
S 2 2 5 6 3 0 1 0.5 plate_right
S 3 7 10 9 8 0 0 0.8 square
End
)");
    const auto r = run_ffcube("formfactors " + (dir / "halves.vs3") + " --no-subdivide -q --view3d " + (dir / "vf.txt") +
                              " -o " + (dir / "F.mtx") + " --patch-table " + (dir / "p.csv") + " --elmer " + (dir / "vf.dat"));
    ASSERT_EQ(r.code, 0) << r.output;
    const View3dText f = read_view3d(read_text(dir / "vf.txt"));
    EXPECT_EQ(f.format, 0);
    EXPECT_EQ(f.encl, 0);
    EXPECT_EQ(f.emit, 0);
    ASSERT_EQ(f.n, 2u);  // renumbered after combination: plate, square
    EXPECT_NEAR(f.area[0], 1.0, 1e-6);
    EXPECT_NEAR(f.area[1], 1.0, 1e-6);
    const double exact = ff_parallel_rectangles(1.0, 1.0, 1.0);
    // Near, unoccluded pairs: exact values (see SkyCli); the file's %.6f adds 5e-7.
    EXPECT_NEAR(f.F[0][1], exact, 1.5e-6);
    EXPECT_NEAR(f.F[1][0], exact, 1.5e-6);
    EXPECT_EQ(f.F[0][0], 0.0);
    EXPECT_EQ(f.F[1][1], 0.0);
    // Emissivities: the plate's is the area-weighted mean of its halves' (0.9 and 0.5).
    EXPECT_NEAR(f.emissivity[0], 0.7, 5e-4);
    EXPECT_NEAR(f.emissivity[1], 0.8, 5e-4);

    // The same rule by hand from the patch matrix: F(plate→square) = (A1 F13 + A2 F23)/(A1 + A2),
    // F(square→plate) = F31 + F32.
    std::map<std::pair<int, int>, double> m;
    {
        std::istringstream in(read_text(dir / "F.mtx"));
        std::string line;
        while (std::getline(in, line) && line[0] == '%') {
        }
        int i, j;
        double v;
        while (in >> i >> j >> v) m[{i, j}] = v;
    }
    const auto at = [&](int i, int j) { return m[std::pair{i, j}]; };
    // The file's %.6f (5e-7) and the .mtx's 9 digits (1e-9 here) apart.
    EXPECT_NEAR(f.F[0][1], 0.5 * at(1, 3) + 0.5 * at(2, 3), 5e-7 + 1e-8);
    EXPECT_NEAR(f.F[1][0], at(3, 1) + at(3, 2), 5e-7 + 1e-8);
    // Elmer's file holds the same patch rows, 1-based.
    {
        std::istringstream in(read_text(dir / "vf.dat"));
        std::size_t entries = 0;
        for (int row = 1; row <= 3; ++row) {
            int k;
            ASSERT_TRUE(in >> k);
            for (int e = 0; e < k; ++e) {
                int i, j;
                double v;
                ASSERT_TRUE(in >> i >> j >> v);
                EXPECT_EQ(i, row);
                EXPECT_EQ(v, at(i, j)) << i << " " << j;  // both 9 significant digits of one float
                ++entries;
            }
        }
        EXPECT_EQ(entries, m.size());
    }
    // The patch table maps rows to the input surfaces: the right half's centroid and normal.
    // (Its last column is the row's estimated error, docs/accuracy.md "Accuracy by target".)
    EXPECT_NE(read_text(dir / "p.csv").find("\n1,plate,0.5,0.75,0.5,0,0,0,1,"), std::string::npos) << read_text(dir / "p.csv");
}

TEST(View3dCli, ControlKeysEnclEmitOutAreHonoured) {
    TempDir dir;
    const std::string cube = std::string(kView3dCubeVertices) + kView3dOpenBoxSurfaces + "S 6 5 8 7 6 0 0 0.3 top\nEnd\n";
    // encl=1: closure enforced on a closed cube; the rows of the file sum to 1 up to the six
    // %.6f roundings (6 × 5e-7).
    write_file(dir / "encl.vs3", "C encl=1 eps=1e-6\n" + cube);
    auto r = run_ffcube("formfactors " + (dir / "encl.vs3") + " --no-subdivide -q --view3d " + (dir / "e.txt") + " --report " +
                        (dir / "r.json"));
    ASSERT_EQ(r.code, 0) << r.output;
    View3dText f = read_view3d(read_text(dir / "e.txt"));
    EXPECT_EQ(f.encl, 1);
    ASSERT_EQ(f.n, 6u);
    for (const auto& row : f.F) {
        double s = 0.0;
        for (const double v : row) s += v;
        EXPECT_NEAR(s, 1.0, 3e-6);
    }
    auto report = nlohmann::json::parse(read_text(dir / "r.json"));
    EXPECT_EQ(report["view3d"]["encl_applied"], "closure");
    EXPECT_EQ(report["enforce"]["mode"], "closure");
    // eps sets the accuracy target: nothing is ignored.
    EXPECT_EQ(report["view3d"]["ignored_controls"].size(), 0u);
    EXPECT_DOUBLE_EQ(report["view3d"]["eps"].get<double>(), 1e-6);
    EXPECT_DOUBLE_EQ(report["tolerance"]["target"].get<double>(), 1e-6);

    // emit=1: Hottel's exchange factors; in a closed enclosure row n sums to its emissivity
    // (the rows are closed to 1e-7 by encl=1; then six %.6f roundings).
    write_file(dir / "emit.vs3", "C encl=1 emit=1\n" + cube);
    r = run_ffcube("formfactors " + (dir / "emit.vs3") + " --no-subdivide -q --view3d " + (dir / "x.txt"));
    ASSERT_EQ(r.code, 0) << r.output;
    f = read_view3d(read_text(dir / "x.txt"));
    EXPECT_EQ(f.emit, 1);
    for (std::size_t n = 0; n < f.n; ++n) {
        double s = 0.0;
        for (const double v : f.F[n]) s += v;
        EXPECT_NEAR(s, f.emissivity[n], 3e-6 + 1e-6) << n;
        EXPECT_GT(f.F[n][n], 0.0);  // a flat face absorbs its own reflected light
    }
    EXPECT_NEAR(f.emissivity[5], 0.3, 5e-4);

    // out=1: the binary file, its header exactly 32 bytes as savevf.c writes it.
    write_file(dir / "out.vs3", "C out=1\n" + cube);
    r = run_ffcube("formfactors " + (dir / "out.vs3") + " --no-subdivide -q --view3d " + (dir / "b.vf"));
    ASSERT_EQ(r.code, 0) << r.output;
    const std::string b = read_text(dir / "b.vf");
    ASSERT_EQ(b.size(), 32u + 4u * (6 + 36 + 6));
    EXPECT_EQ(b.substr(0, 30), "View3D 3.5 1 0 0 6" + std::string(30 - 18, ' '));
    EXPECT_EQ(b.substr(30, 2), "\r\n");
    float area0, emit5;
    std::memcpy(&area0, b.data() + 32, 4);
    std::memcpy(&emit5, b.data() + 32 + 4 * (6 + 36 + 5), 4);
    EXPECT_FLOAT_EQ(area0, 1.0f);
    EXPECT_FLOAT_EQ(emit5, 0.3f);
    // --view3d-format text overrides the file's out=1.
    r = run_ffcube("formfactors " + (dir / "out.vs3") + " --no-subdivide -q --view3d " + (dir / "t.vf") + " --view3d-format text");
    ASSERT_EQ(r.code, 0) << r.output;
    EXPECT_EQ(read_text(dir / "t.vf").substr(0, 31), "View3D 3.5 0 0 0 6" + std::string(30 - 18, ' ') + "\n");
}

TEST(View3dCli, BadOutputDirectoryIsRefusedBeforeWork) {
    const auto r = run_ffcube("formfactors " + test::example("parallel_squares.vs3") + " -q --sky /no/such/dir/s.csv");
    EXPECT_EQ(r.code, 2) << r.output;
    EXPECT_NE(r.output.find("--sky /no/such/dir/s.csv: the directory /no/such/dir does not exist"), std::string::npos)
        << r.output;
}

}  // namespace
}  // namespace ffcube
