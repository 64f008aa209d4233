// ffcube sun --sun-series (docs/urban.md, "A day of shortwave"): a plane alone against
// (1 − ρ)(DNI sin(elevation) + DHI); a box on a plane against the closed-form shadow; a day of 96
// steps on a generated city conserving energy each step and solving B = E + ρFB row by row, both
// checked with F read independently from the .ffm; the refusals (exit 2, file:line, no output).
#include <fmt/format.h>
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <map>
#include <sstream>

#include "cli/cli_util.hpp"
#include "ffcube/io/ffm.hpp"
#include "support/box_shadow.hpp"

namespace ffcube::test {
namespace {

const char* kHeader = "time,azimuth,elevation,direct_normal_irradiance,diffuse_horizontal_irradiance\n";

// 8× fewer pixels than the default budget (2^27), for speed: tests/cli/test_sun_cli.cpp measured the
// box's fractions within 1.9e-5 at the default; a pixel √8 larger moves edge errors that grow like
// h² log(L/h) (gl/sun_buffer.cpp) by about 8×, still far below the 1e-3 tolerance used here.
const std::string kBudget = " --set max-pixels=16777216";

struct Row {
    std::string time, object;
    std::size_t patch = 0;
    double area = 0, albedo = 0, direct = 0, diffuse = 0, reflected = 0, absorbed = 0;
};

// time,patch,object,area,albedo,direct,diffuse,reflected,absorbed (no quoted names in these tests).
std::vector<Row> read_rows(const std::string& text) {
    std::istringstream in(text);
    std::string line;
    std::getline(in, line);
    EXPECT_EQ(line, "time,patch,object,area,albedo,direct,diffuse,reflected,absorbed");
    std::vector<Row> out;
    while (std::getline(in, line)) {
        std::vector<std::string> f;
        std::stringstream ls(line);
        for (std::string x; std::getline(ls, x, ',');) f.push_back(x);
        EXPECT_EQ(f.size(), 9u) << line;
        if (f.size() != 9) break;
        out.push_back({f[0], f[2], std::stoul(f[1]), std::stod(f[3]), std::stod(f[4]), std::stod(f[5]), std::stod(f[6]),
                       std::stod(f[7]), std::stod(f[8])});
    }
    return out;
}

TEST(SunSeriesCli, APlaneAloneAbsorbsTheClosedForm) {
    TempDir dir;
    write_file(dir / "plane.obj", "o ground\nv -5 -5 0\nv 5 -5 0\nv 5 5 0\nv -5 5 0\nf 1 2 3 4\n");
    write_file(dir / "a.csv", "object,albedo\nground,0.2\n");
    write_file(dir / "sun.csv", std::string(kHeader) + "t1,135,35,800,120\nt2,0,5,300,40\nnight,0,-10,0,0\nt3,250,80,900,0\n");
    const std::map<std::string, std::array<double, 3>> steps = {
        {"t1", {35, 800, 120}}, {"t2", {5, 300, 40}}, {"night", {-10, 0, 0}}, {"t3", {80, 900, 0}}};
    for (const char* sky : {"isotropic", "tregenza"}) {
        const RunResult r = run_ffcube("sun " + (dir / "plane.obj") + " --no-subdivide -q --sun-series " + (dir / "sun.csv") +
                                       " --albedo " + (dir / "a.csv") + " --sky-patches " + sky + " -o " + (dir / "sw.csv") + kBudget +
                                       (std::string(sky) == "tregenza" ? " --sky-patches-out " + (dir / "v.csv") : ""));
        ASSERT_EQ(r.code, 0) << r.output;
        if (std::string(sky) == "tregenza") {
            // The Tregenza layout (8 bands of 12°: 30, 30, 24, 24, 18, 12, 6 patches, and the cap):
            // an unobstructed horizontal patch sees band patch p as (Δaz/2π)(sin² alt1 − sin² alt0).
            std::vector<double> want;
            const int counts[8] = {30, 30, 24, 24, 18, 12, 6, 1};
            for (int b = 0; b < 8; ++b) {
                const double a0 = b * 12.0 * M_PI / 180, a1 = b < 7 ? (b + 1) * 12.0 * M_PI / 180 : M_PI / 2;
                for (int k = 0; k < counts[b]; ++k)
                    want.push_back((std::pow(std::sin(a1), 2) - std::pow(std::sin(a0), 2)) / counts[b]);
            }
            std::istringstream v(read_text(dir / "v.csv"));
            std::string line;
            std::getline(v, line);
            ASSERT_EQ(line.substr(0, 22), "patch,object,p0,p1,p2,");
            std::getline(v, line);
            std::vector<double> got;
            std::stringstream ls(line);
            for (std::string x; std::getline(ls, x, ',');) got.push_back(std::atof(x.c_str()));  // patch, object, V
            ASSERT_EQ(got.size(), 2 + want.size()) << line;
            double sum = 0.0;
            for (std::size_t p = 0; p < want.size(); ++p) {
                EXPECT_NEAR(got[2 + p], want[p], 1e-12) << "sky patch " << p;  // 12 digits printed
                sum += got[2 + p];
            }
            EXPECT_NEAR(sum, 1.0, 1e-10);
        }
        const std::vector<Row> rows = read_rows(read_text(dir / "sw.csv"));
        ASSERT_EQ(rows.size(), 4u);
        for (const Row& x : rows) {
            const auto [el, dni, dhi] = steps.at(x.time);
            const double beam = el > 0 ? dni * std::sin(el * M_PI / 180) : 0.0;
            // The direct share is a pixel count: within the sun item buffer's tolerance 1e-3 (docs/urban.md).
            EXPECT_NEAR(x.direct, beam, 1e-3 * beam + 1e-12) << sky << " " << x.time;
            // The sky view factor of a plane alone is 1: exact by both methods (rows empty; the
            // Tregenza cells of a horizontal patch are exact, tests/raycast/test_sky_patches.cpp).
            EXPECT_NEAR(x.diffuse, dhi, 1e-12 * dhi) << sky << " " << x.time;
            EXPECT_EQ(x.reflected, 0.0);
            EXPECT_NEAR(x.absorbed, (1 - 0.2) * (beam + dhi), 1e-3 * beam + 1e-12 * dhi) << sky << " " << x.time;
        }
    }
}

TEST(SunSeriesCli, ABoxOnAPlaneGetsTheAnalyticShadow) {
    TempDir dir;
    write_file(dir / "box.obj", kBoxOnPlane);
    // Albedo 0 and no sky: what each face absorbs is the direct beam alone, DNI × f × cos θ.
    write_file(dir / "a.csv", "object,albedo\nground,0\nroof,0\nsouth,0\neast,0\nnorth,0\nwest,0\n");
    std::string series = kHeader;
    for (const auto& [az, el] : kSunPositions) series += fmt::format("{}-{},{},{},1000,0\n", az, el, az, el);
    write_file(dir / "sun.csv", series);
    const RunResult r = run_ffcube("sun " + (dir / "box.obj") + " --no-subdivide -q --sun-series " + (dir / "sun.csv") +
                                   " --albedo " + (dir / "a.csv") + " -o " + (dir / "sw.csv") + kBudget);
    ASSERT_EQ(r.code, 0) << r.output;
    const std::map<std::string, std::array<double, 3>> normal = {{"ground", {0, 0, 1}}, {"roof", {0, 0, 1}},
                                                                  {"south", {0, -1, 0}}, {"east", {1, 0, 0}},
                                                                  {"north", {0, 1, 0}},  {"west", {-1, 0, 0}}};
    const std::vector<Row> rows = read_rows(read_text(dir / "sw.csv"));
    ASSERT_EQ(rows.size(), kSunPositions.size() * 6);
    for (const Row& x : rows) {
        const std::size_t dash = x.time.find('-');
        const auto s = sun_from_angles(std::stod(x.time.substr(0, dash)), std::stod(x.time.substr(dash + 1)));
        const auto& n = normal.at(x.object);
        const double c = n[0] * s[0] + n[1] * s[1] + n[2] * s[2];
        double f = c > 1e-9 ? 1.0 : 0.0;
        if (x.object == "ground") f = 1.0 - box_shadow_on_ground(s[0], s[1], s[2]) / 100.0;
        const double want = 1000.0 * f * std::max(c, 0.0);
        // The sunlit fractions' tolerance 1e-3 (tests/cli/test_sun_cli.cpp) times DNI cos θ.
        EXPECT_NEAR(x.direct, want, 1e-3 * 1000.0 * std::max(c, 0.0) + 1e-12) << x.time << " " << x.object;
        EXPECT_EQ(x.reflected, 0.0);
        EXPECT_EQ(x.absorbed, x.direct);
    }
}

TEST(SunSeriesCli, ADayOnACityConservesEnergyEachStepAndSolvesTheReflections) {
    TempDir dir;
    const std::string city = dir / "city.stl";
    ASSERT_EQ(gen_city(city, 400, 3), 0);
    const std::string ffm = dir / "F.ffm";
    // F's accuracy does not matter here (the checks use the same F): 2,048 rays a patch, for speed.
    RunResult r = run_ffcube("formfactors " + city + " --no-subdivide -q --method raycast --rays 2048 -o " + ffm);
    ASSERT_EQ(r.code, 0) << r.output;
    write_file(dir / "a.csv", "object,albedo\ncity,0.3\n");
    // 96 quarter hours of a clear day: the sun from east to west, up to 60°.
    std::string series = kHeader;
    std::map<std::string, double> dhi_of;
    for (int k = 0; k < 96; ++k) {
        const double h = k / 4.0, el = 60.0 * std::sin(M_PI * (h - 6.0) / 12.0), az = std::fmod(180.0 + 15.0 * (h - 12.0) + 360.0, 360.0);
        const double dni = el > 0 ? 850.0 * std::pow(std::sin(el * M_PI / 180), 0.3) : 0.0;
        // As written to the file (6 decimals), so that the test compares with what ffcube read.
        const double dhi = std::stod(fmt::format("{:.6f}", el > 0 ? 110.0 * std::sin(el * M_PI / 180) + 5.0 : 0.0));
        const std::string t = fmt::format("{:05.2f}", h);
        dhi_of[t] = dhi;
        series += fmt::format("{},{:.6f},{:.6f},{:.6f},{:.6f}\n", t, az, el, dni, dhi);
    }
    write_file(dir / "sun.csv", series);
    r = run_ffcube("sun " + city + " --no-subdivide -q --sun-series " + (dir / "sun.csv") + " --albedo " + (dir / "a.csv") +
                   " --matrix " + ffm + " -o " + (dir / "sw.csv") + " --set max-pixels=1048576");
    ASSERT_EQ(r.code, 0) << r.output;

    const FfmFile f = read_ffm(ffm);
    const CsrMatrix& F = f.matrix;
    const std::uint32_t n = F.size();
    ASSERT_EQ(n, 400u);
    const std::vector<Row> rows = read_rows(read_text(dir / "sw.csv"));
    ASSERT_EQ(rows.size(), 96u * n);
    std::vector<double> row_sum(n);
    for (std::uint32_t j = 0; j < n; ++j) row_sum[j] = F.row(j).sum();
    std::size_t daylight = 0;
    for (std::size_t s = 0; s < 96; ++s) {
        const Row* step = &rows[s * n];
        double incident = 0, absorbed = 0, escaped = 0;
        std::vector<double> leaving(n), arriving(n, 0.0);  // W: ρ A (d + f + r), and Fᵀ of it
        for (std::uint32_t i = 0; i < n; ++i) {
            const Row& x = step[i];
            ASSERT_EQ(x.patch, i);
            ASSERT_EQ(x.time, step[0].time);
            const double in = x.direct + x.diffuse;
            incident += x.area * in;
            absorbed += x.area * x.absorbed;
            leaving[i] = x.albedo * x.area * (in + x.reflected);
            escaped += leaving[i] * (1.0 - row_sum[i]);
            // The isotropic sky: DHI × (1 − row sum), clamped at 0 (formfactor/sky.hpp); 12 digits printed.
            EXPECT_NEAR(x.diffuse, dhi_of.at(x.time) * std::max(0.0, 1.0 - row_sum[i]), 1e-11 * dhi_of.at(x.time) + 1e-300);
            EXPECT_NEAR(x.absorbed, (1.0 - x.albedo) * (in + x.reflected), 1e-11 * (in + x.reflected) + 1e-300);
        }
        if (incident == 0.0) continue;
        ++daylight;
        for (std::uint32_t j = 0; j < n; ++j) {
            const RowView row = F.row(j);
            for (std::size_t e = 0; e < row.col.size(); ++e) arriving[row.col[e]] += row.val[e] * leaving[j];
        }
        // The balance (the 1e-9): the solver closes it to ~1e-12 (its default tolerance, solver/shortwave.hpp), and
        // the file's 12 significant digits add at most 5e-12 relative per value.
        EXPECT_NEAR(absorbed + escaped, incident, 1e-9 * incident) << step[0].time;
        // Every row of B = E + ρFB: what arrives at i from reflections is Σ_j F_ji ρ_j A_j H_j. The
        // sweeps stop when the change is below 1e-12 Σ Q; printing adds 5e-12 relative: 1e-9 Σ Q.
        for (std::uint32_t i = 0; i < n; ++i)
            EXPECT_NEAR(step[i].area * step[i].reflected, arriving[i], 1e-9 * incident) << step[0].time << " patch " << i;
    }
    EXPECT_GT(daylight, 40u);
}

TEST(SunSeriesCli, RefusesBadInputWithExit2AndNoOutput) {
    TempDir dir;
    write_file(dir / "plane.obj", "o ground\nv -5 -5 0\nv 5 -5 0\nv 5 5 0\nv -5 5 0\nf 1 2 3 4\n");
    write_file(dir / "other.obj", "o ground\nv -5 -5 0\nv 6 -5 0\nv 5 5 0\nv -5 5 0\nf 1 2 3 4\n");
    write_file(dir / "a.csv", "object,albedo\nground,0.2\n");
    write_file(dir / "sun.csv", std::string(kHeader) + "t1,135,35,800,120\n");
    ASSERT_EQ(run_ffcube("formfactors " + (dir / "other.obj") + " --no-subdivide -q -o " + (dir / "other.ffm")).code, 0);
    write_file(dir / "bad_sun.csv", std::string(kHeader) + "t1,135,35,800,120\nt2,135,95,800,120\n");
    write_file(dir / "bad_albedo.csv", "object,albedo\nground,0.2\ntree,0.1\n");
    write_file(dir / "one.csv", "object,albedo\nground,1\n");
    const std::string base = "sun " + (dir / "plane.obj") + " --no-subdivide -q -o " + (dir / "out.csv") + " ";
    const std::vector<std::pair<std::string, std::string>> cases = {
        {"--sun-series " + (dir / "bad_sun.csv") + " --albedo " + (dir / "a.csv"), "bad_sun.csv:3: elevation 95 must be in [-90, 90]"},
        {"--sun-series " + (dir / "sun.csv") + " --albedo " + (dir / "bad_albedo.csv"), "bad_albedo.csv:3: the scene has no object 'tree'"},
        {"--sun-series " + (dir / "sun.csv") + " --albedo " + (dir / "one.csv"), "one.csv:2: albedo 1 of 'ground' must be in [0, 1)"},
        {"--sun-series " + (dir / "sun.csv"), "--sun-series needs --albedo"},
        {"--sun-series " + (dir / "sun.csv") + " --albedo " + (dir / "a.csv") + " --sun 10,10", "leave out --sun"},
        {"--sun 10,10 --albedo " + (dir / "a.csv"), "--albedo goes with --sun-series"},
        {"--sun-series " + (dir / "sun.csv") + " --albedo " + (dir / "a.csv") + " --sky-patches perez", "--sky-patches perez"},
        {"--sun-series " + (dir / "sun.csv") + " --albedo " + (dir / "a.csv") + " --sky-patches-out " + (dir / "v.csv"),
         "give --sky-patches tregenza"},
        {"--sun-series " + (dir / "missing.csv") + " --albedo " + (dir / "a.csv"), "missing.csv"},
        {"--sun-series " + (dir / "sun.csv") + " --albedo " + (dir / "a.csv") + " --matrix " + (dir / "other.ffm"), "other.ffm"},
    };
    for (const auto& [args, want] : cases) {
        const RunResult r = run_ffcube(base + args);
        EXPECT_EQ(r.code, 2) << args << "\n" << r.output;
        EXPECT_NE(r.output.find(want), std::string::npos) << "want '" << want << "' in:\n" << r.output;
        EXPECT_FALSE(std::filesystem::exists(dir / "out.csv")) << args;
    }
}

}  // namespace
}  // namespace ffcube::test
