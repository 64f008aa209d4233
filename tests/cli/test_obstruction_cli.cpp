// View3D's obstruction-only surfaces (O lines; docs/scene-format.md), through the real binary:
// they block from both sides, get no row and no column in any output, and what they intercept is
// neither in F nor sky. Checked against closed forms (Howell C-11, C-12, C-14) and, where a plate
// hides part of a view, against the ray caster.
#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <map>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>
#include <vector>

#include "cli/cli_util.hpp"
#include "support/view3d_text.hpp"
#include "ffcube/reference/closed_forms.hpp"
#include "ffcube/geometry/analytic.hpp"

namespace ffcube {
namespace {

using test::read_text;
using test::run_ffcube;
using test::last_column_by_first;
using test::TempDir;
using test::write_file;

// "from,to,F" (--groups) → (from, to) → F.
std::map<std::pair<std::string, std::string>, double> groups(const std::string& text) {
    std::map<std::pair<std::string, std::string>, double> m;
    std::istringstream in(text);
    std::string line;
    std::getline(in, line);  // header
    while (std::getline(in, line)) {
        const auto a = line.find(','), b = line.find(',', a + 1);
        m[{line.substr(0, a), line.substr(a + 1, b - a - 1)}] = std::stod(line.substr(b + 1));
    }
    return m;
}

std::size_t lines(const std::string& text) {
    std::size_t n = 0;
    for (const char c : text) n += c == '\n';
    return n;
}

// The unit cube's corners; the open box's five faces facing inward; the lid as an O surface
// (written facing outward: an O surface blocks and intercepts from both sides, whatever its
// winding).
const std::string kBox = std::string(test::kView3dCubeVertices) + R"(S 1 1 2 3 4 0 0 0.9 floor
S 2 1 5 6 2 0 0 0.9 south
S 3 4 3 7 8 0 0 0.9 north
O 4 5 6 7 8 0 0 0.9 lid
S 5 1 4 8 5 0 0 0.9 west
S 6 2 6 7 3 0 0 0.9 east
End
)";

TEST(ObstructionCli, ALidClosesTheOpenBoxsSkyAndLeavesFAsItWas) {
    TempDir dir;
    write_file(dir / "box.vs3", kBox);
    const auto r = run_ffcube("formfactors " + (dir / "box.vs3") + " --no-subdivide -q --view3d " + (dir / "vf.txt") + " -o " +
                              (dir / "F.mtx") + " --sky " + (dir / "sky.csv") + " --sky-by object --patch-table " +
                              (dir / "p.csv") + " --elmer " + (dir / "vf.dat") + " --groups " + (dir / "g.csv") +
                              " --report " + (dir / "r.json"));
    ASSERT_EQ(r.code, 0) << r.output;
    // No row, no column: five surfaces everywhere.
    const test::View3dText vf = test::read_view3d(read_text(dir / "vf.txt"));
    const std::size_t n = vf.n;
    ASSERT_EQ(n, 5u);
    const auto& F = vf.F;
    {
        std::istringstream mtx(read_text(dir / "F.mtx"));
        std::string line;
        while (std::getline(mtx, line) && line[0] == '%') {
        }
        EXPECT_EQ(line.rfind("5 5 ", 0), 0u) << line;  // 5 × 5
    }
    EXPECT_EQ(lines(read_text(dir / "p.csv")), 1u + 5u);
    EXPECT_EQ(read_text(dir / "p.csv").find("lid"), std::string::npos);
    EXPECT_EQ(read_text(dir / "g.csv").find("lid"), std::string::npos);
    EXPECT_EQ(read_text(dir / "sky.csv").find("lid"), std::string::npos);
    // Elmer: five rows, and no index above 5.
    {
        std::istringstream in(read_text(dir / "vf.dat"));
        for (int row = 1; row <= 5; ++row) {
            int k;
            ASSERT_TRUE(in >> k);
            for (int e = 0; e < k; ++e) {
                int i, j;
                double v;
                ASSERT_TRUE(in >> i >> j >> v);
                EXPECT_EQ(i, row);
                EXPECT_LE(j, 5);
            }
        }
        int more;
        EXPECT_FALSE(in >> more);
    }
    // F among the five is the open box's, in closed form: floor → wall = (1 − C-11)/4 (the floor
    // sees the four walls and the opening, the walls alike by symmetry); wall → floor = C-14;
    // wall → opposite wall = C-11; wall → side wall = (1 − 2 C-14 − C-11)/2. Every pair is near
    // and (the lid lies on the box's boundary, inside no pair's hull) unoccluded, so the default
    // correction gives exact values: what is left is float storage and the file's %.6f (5e-7).
    const double c11 = ff_parallel_rectangles(1, 1, 1), c14 = ff_perpendicular_rectangles_common_edge(1, 1, 1);
    const std::map<std::string, std::size_t> at = {{"floor", 0}, {"south", 1}, {"north", 2}, {"west", 3}, {"east", 4}};
    const double tol = 5e-7 + 1e-7;
    EXPECT_NEAR(F[at.at("floor")][at.at("south")], (1 - c11) / 4, tol);
    EXPECT_NEAR(F[at.at("south")][at.at("floor")], c14, tol);
    EXPECT_NEAR(F[at.at("south")][at.at("north")], c11, tol);
    EXPECT_NEAR(F[at.at("south")][at.at("west")], (1 - 2 * c14 - c11) / 2, tol);
    // Rows sum to 1 less what the lid intercepts (C-11 from the floor, C-14 from a wall).
    double floor_sum = 0, south_sum = 0;
    for (std::size_t j = 0; j < n; ++j) floor_sum += F[0][j], south_sum += F[1][j];
    EXPECT_NEAR(floor_sum, 1 - c11, 5 * tol);
    EXPECT_NEAR(south_sum, 1 - c14, 5 * tol);
    // The lid closes the box: no sky anywhere (1 − Σ F − intercepted, the sum of exact values
    // stored as float: a few 1e-8).
    const auto sky = last_column_by_first(read_text(dir / "sky.csv"));
    ASSERT_EQ(sky.size(), 5u);
    for (const auto& [name, v] : sky) EXPECT_NEAR(v, 0.0, 1e-6) << name;
    const auto report = nlohmann::json::parse(read_text(dir / "r.json"));
    EXPECT_EQ(report["patches"].get<int>(), 5);
    EXPECT_EQ(report["obstruction"]["surfaces"].get<int>(), 1);
    EXPECT_EQ(report["obstruction"]["rows_not_computed"].get<int>(), 2);  // the lid's two sides
    EXPECT_NEAR(report["sky"]["max"].get<double>(), 0.0, 1e-6);
    // The ray caster, an independent method, gives the same closed sky: every ray that leaves the
    // box's inside ends on a surface, the lid's from either side.
    const auto rc = run_ffcube("formfactors " + (dir / "box.vs3") + " --no-subdivide -q --method raycast --rays 4096 --sky " +
                               (dir / "rsky.csv") + " --sky-by object");
    ASSERT_EQ(rc.code, 0) << rc.output;
    // A ray can only escape through float rounding at the box's edges; the near-field correction
    // replaces every entry by its exact value here anyway.
    for (const auto& [name, v] : last_column_by_first(read_text(dir / "rsky.csv"))) EXPECT_NEAR(v, 0.0, 1e-6) << name;
    // Closure makes no sense with energy absorbed outside the rows: refused.
    const auto closed = run_ffcube("formfactors " + (dir / "box.vs3") + " --no-subdivide -q --enforce closure");
    EXPECT_EQ(closed.code, 2) << closed.output;
    EXPECT_NE(closed.output.find("obstruction-only surfaces (O)"), std::string::npos) << closed.output;
}

// Two opposed unit squares at distance 1 and, halfway, an O plate 3 × 3 that hides each from the
// other completely: F = 0 exactly, and each square's sky is 1 − its factor to the plate, a
// parallel rectangle offset (Howell C-12) at distance 0.5.
const std::string kHidden = std::string(test::kView3dCubeVertices) + R"(V 9 -1 -1 0.5
V 10 2 -1 0.5
V 11 2 2 0.5
V 12 -1 2 0.5
S 1 1 2 3 4 0 0 0.9 lower
O 2 9 10 11 12 0 0 0.9 plate
S 3 5 8 7 6 0 0 0.9 upper
End
)";

TEST(ObstructionCli, APlateBetweenTwoSquaresHidesThemExactly) {
    TempDir dir;
    write_file(dir / "hidden.vs3", kHidden);
    const double svf = 1.0 - ff_parallel_rectangles_offset(0, 1, 0, 1, -1, 2, -1, 2, 0.5);
    const int rays = 40000;
    for (const std::string method : {"hemicube", "raycast"}) {
        const auto r = run_ffcube("formfactors " + (dir / "hidden.vs3") + " --max-patch-edge 0.5 -q --method " + method +
                                  (method == "raycast" ? " --rays " + std::to_string(rays) : std::string()) + " --groups " +
                                  (dir / "g.csv") + " --sky " +
                                  (dir / "sky.csv") + " --sky-by object --report " + (dir / "r.json"));
        ASSERT_EQ(r.code, 0) << method << r.output;
        // Nothing of one square reaches the other: no entry at all (a pixel or a ray that got
        // past the plate would make one).
        const auto g = groups(read_text(dir / "g.csv"));
        EXPECT_TRUE(g.empty()) << method << "\n" << read_text(dir / "g.csv");
        // The squares' sky. Hemicube: its per-row error estimate bounds Σ_j |F_ij − exact_ij|
        // (docs/accuracy.md), so also the error of 1 − Σ_j F_ij and of its area-weighted mean
        // over an object; 1e-6 more for the CSV's digits and float storage. Ray caster: each
        // patch's sky is a mean of N Bernoulli draws (standard error ≤ 0.5/√N; the square's 4
        // patches average it to 0.5/√(4N) = 1.25e-3 at N = 40000), 5 sigma; the near entries the
        // correction makes exact only lower it.
        const auto report = nlohmann::json::parse(read_text(dir / "r.json"));
        const double tol = method == "hemicube" ? report["row_error_estimate"]["max"].get<double>() + 1e-6
                                                : 5 * 0.5 / std::sqrt(4.0 * rays);
        const auto sky = last_column_by_first(read_text(dir / "sky.csv"));
        ASSERT_EQ(sky.size(), 2u) << method;
        std::printf("%s: sky lower %.6f upper %.6f exact %.6f (tolerance %.2e)\n", method.c_str(), sky.at("lower"),
                    sky.at("upper"), svf, tol);
        EXPECT_NEAR(sky.at("lower"), svf, tol) << method;
        EXPECT_NEAR(sky.at("upper"), svf, tol) << method;
    }
}

// A plate over half of the lower square's view: the hemicube and the ray caster agree on F and
// on the sky, per object, within their derived errors.
const std::string kHalf = std::string(test::kView3dCubeVertices) + R"(V 9 -1 -1 0.5
V 10 0.5 -1 0.5
V 11 0.5 2 0.5
V 12 -1 2 0.5
S 1 1 2 3 4 0 0 0.9 lower
S 2 5 8 7 6 0 0 0.9 upper
O 3 12 11 10 9 0 0 0.9 plate
End
)";

TEST(ObstructionCli, APlateOverHalfTheViewAgreesWithTheRayCaster) {
    TempDir dir;
    write_file(dir / "half.vs3", kHalf);
    const std::string common = "formfactors " + (dir / "half.vs3") + " --max-patch-edge 0.25 -q";
    auto r = run_ffcube(common + " --groups " + (dir / "h.csv") + " --sky " + (dir / "hs.csv") + " --sky-by object --report " +
                        (dir / "r.json"));
    ASSERT_EQ(r.code, 0) << r.output;
    const int rays = 20000;
    r = run_ffcube(common + " --method raycast --correct none --rays " + std::to_string(rays) + " --groups " + (dir / "rc.csv") +
                   " --sky " + (dir / "rs.csv") + " --sky-by object");
    ASSERT_EQ(r.code, 0) << r.output;
    const auto h = groups(read_text(dir / "h.csv")), rc = groups(read_text(dir / "rc.csv"));
    const auto hs = last_column_by_first(read_text(dir / "hs.csv")), rs = last_column_by_first(read_text(dir / "rs.csv"));
    const auto report = nlohmann::json::parse(read_text(dir / "r.json"));
    // The hemicube's own error: its per-row estimate bounds Σ_j |F_ij − exact| of every row
    // (docs/accuracy.md), so an object's area-weighted mean entry, and its sky, err by at most
    // the largest row's estimate.
    const double hemicube = report["row_error_estimate"]["max"].get<double>();
    // The ray caster's: an object's F (or sky) is the mean over its 16 patches of N-ray Bernoulli
    // means, standard error ≤ 0.5/√(16 N) = 8.8e-4 at N = 20000; 5 sigma.
    const double raycast = 5 * 0.5 / std::sqrt(16.0 * rays);
    const std::pair<std::string, std::string> lu{"lower", "upper"}, ul{"upper", "lower"};
    ASSERT_TRUE(h.count(lu) && rc.count(lu) && h.count(ul) && rc.count(ul));
    std::printf("half-hidden squares: F(lower->upper) hemicube %.6f raycast %.6f; sky lower %.6f / %.6f; bound %.2e + %.2e\n",
                h.at(lu), rc.at(lu), hs.at("lower"), rs.at("lower"), hemicube, raycast);
    // The plate hides a good part of the view: F well below the unobstructed C-11.
    EXPECT_LT(h.at(lu), 0.75 * ff_parallel_rectangles(1, 1, 1));
    EXPECT_NEAR(h.at(lu), rc.at(lu), hemicube + raycast);
    EXPECT_NEAR(h.at(ul), rc.at(ul), hemicube + raycast);
    EXPECT_NEAR(hs.at("lower"), rs.at("lower"), hemicube + raycast);
    EXPECT_NEAR(hs.at("upper"), rs.at("upper"), hemicube + raycast);
}

// Adaptive meshing stays refused on such scenes (it refines the radiating patches only, and the
// drawn scene would lose its obstructions), naming the file; --checkpoint and mpirun work
// (tests/cli/test_obstruction_resume_cli.cpp, tests/mpi/mpi_obstructions.sh).
TEST(ObstructionCli, UnsupportedCombinationsAreRefused) {
    TempDir dir;
    write_file(dir / "box.vs3", kBox);
    const auto r = run_ffcube("solve " + (dir / "box.vs3") + " -q --target-error 0.05 --max-elements 100");
    EXPECT_EQ(r.code, 2) << r.output;
    EXPECT_NE(r.output.find("adaptive meshing: " + (dir / "box.vs3") + " has obstruction-only surfaces (O): not supported yet"),
              std::string::npos)
        << r.output;
}

}  // namespace
}  // namespace ffcube
