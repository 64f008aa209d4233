// ffcube radiate against closed forms: a small cube inside a closed box (a two-surface enclosure,
// F computed by ffcube), an open plate under the sky, and the refusals (exit 2 naming file:line,
// exit 5 for a solve that does not converge), never writing a result file when it refuses.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <iostream>
#include <map>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <sstream>

#include "cli/cli_util.hpp"

namespace ffcube::test {
namespace {

constexpr double kSigma = 5.670374419e-8;

// The six faces of the cube [−h, h]³ as one OBJ object, facing out (or in).
std::string cube_obj(const std::string& name, double h, bool outward, int& next_vertex) {
    std::ostringstream s;
    s << "o " << name << "\n";
    for (int a = 0; a < 3; ++a)
        for (const int sign : {-1, 1}) {
            const int u = (a + 1) % 3, v = (a + 2) % 3;  // (u, v, a) right-handed: u × v = +a
            const double uv[4][2] = {{-h, -h}, {h, -h}, {h, h}, {-h, h}};
            for (const auto& c : uv) {
                double p[3];
                p[a] = sign * h;
                p[u] = c[0];
                p[v] = c[1];
                s << "v " << p[0] << ' ' << p[1] << ' ' << p[2] << "\n";
            }
            const int b = next_vertex;
            next_vertex += 4;
            // CCW from the side the face looks to: +a order faces +a.
            const bool along_plus = (sign > 0) == outward;
            if (along_plus)
                s << "f " << b << ' ' << b + 1 << ' ' << b + 2 << ' ' << b + 3 << "\n";
            else
                s << "f " << b + 3 << ' ' << b + 2 << ' ' << b + 1 << ' ' << b << "\n";
        }
    return s.str();
}

// name → the CSV's column `column` (header names it), for lines keyed by their first field.
std::map<std::string, double> column(const std::string& text, const std::string& name) {
    std::istringstream in(text);
    std::string line;
    std::getline(in, line);
    std::vector<std::string> header;
    for (std::stringstream h(line); std::getline(h, line, ',');) header.push_back(line);
    const std::size_t k = std::find(header.begin(), header.end(), name) - header.begin();
    std::map<std::string, double> m;
    while (std::getline(in, line)) {
        std::vector<std::string> f;
        for (std::stringstream l(line); std::getline(l, line, ',');) f.push_back(line);
        if (k < f.size()) m[f[0]] = std::stod(f[k]);
    }
    return m;
}

class RadiateCli : public testing::Test {
protected:
    void SetUp() override {
        int next = 1;
        const std::string inner = cube_obj("inner", 0.5, true, next);  // first: vertices 1..24
        write_file(dir / "box.obj", inner + cube_obj("outer", 2.0, false, next));
    }
    TempDir dir;
};

// Inner cube (A1 = 6 m², convex, facing out) in the box (A2 = 96 m², facing in): two-surface
// enclosure, q1 A1 = σ(T1⁴ − T2⁴) A1 / (1/ε1 + (A1/A2)(1/ε2 − 1)).
TEST_F(RadiateCli, InnerCubeInClosedBoxMatchesTwoSurfaceFormula) {
    // F once (--matrix reuse), its row sums in the report.
    const RunResult ff = run_ffcube("formfactors " + (dir / "box.obj") + " --max-patch-edge 1 -q -o " + (dir / "F.ffm") +
                                    " --report " + (dir / "ff.json"));
    ASSERT_EQ(ff.code, 0) << ff.output;
    const double t1 = 800.0, t2 = 300.0, a1 = 6.0, a2 = 96.0;
    for (const double e2 : {1.0, 0.5}) {
        const double e1 = 0.4;
        SCOPED_TRACE(testing::Message() << "eps2 " << e2);
        write_file(dir / "s.csv", "object,emissivity,temperature,heat_flux\ninner," + std::to_string(e1) + "," +
                                      std::to_string(t1) + ",\nouter," + std::to_string(e2) + "," + std::to_string(t2) + ",\n");
        const RunResult r = run_ffcube("radiate " + (dir / "box.obj") + " --max-patch-edge 1 -q --matrix " + (dir / "F.ffm") +
                                       " --surfaces " + (dir / "s.csv") + " -o " + (dir / "q.csv") + " --patch-out " +
                                       (dir / "p.csv") + " --conductances " + (dir / "g.csv") + " --report " + (dir / "r.json"));
        ASSERT_EQ(r.code, 0) << r.output;
        const auto report = nlohmann::json::parse(read_text(dir / "r.json"));
        const double smin = report["row_sums"]["min"], smax = report["row_sums"]["max"];
        const double delta = std::max(1.0 - smin, smax - 1.0);
        // J spread over the outer box's patches (rows of p.csv with object "outer").
        double jmin = 1e300, jmax = 0.0;
        {
            std::istringstream in(read_text(dir / "p.csv"));
            std::string line;
            std::getline(in, line);
            while (std::getline(in, line)) {
                std::vector<std::string> f;
                for (std::stringstream l(line); std::getline(l, line, ',');) f.push_back(line);
                if (f[1] != "outer") continue;
                jmin = std::min(jmin, std::stod(f[5]));
                jmax = std::max(jmax, std::stod(f[5]));
            }
        }
        const double q1 = column(read_text(dir / "q.csv"), "heat_flux").at("inner");
        const double closed = kSigma * (std::pow(t1, 4) - std::pow(t2, 4)) / (1.0 / e1 + (a1 / a2) * (1.0 / e2 - 1.0));
        // Tolerance, from F's own accuracy. The inner cube is convex: its rows see only outer patches,
        // so its mean irradiation G1 = Σ_i A_i Σ_j F_ij J_j / A1 lies in [s_min J2min, s_max J2max]
        // (s: row sums). The closed form assumes a uniform J2*, and J2* − J2mean = ((1 − ε2)/ε2)
        // (A1 (q1* − q1) ± e)/A2 by energy conservation (J2mean = σT2⁴ + ((1 − ε2)/ε2) × mean absorbed
        // flux), e the balance error in W (relative_error × absolute_power: the rows' reciprocity).
        // With q1 = ε1 (σT1⁴ − G1):
        //   |q1 − q1*| ≤ ε1 [ (J2max − J2min) + δ J2max + ((1 − ε2)/ε2) e/A2 ] / (1 − ε1 ((1 − ε2)/ε2) A1/A2),
        // δ = max |1 − s|. With ε2 = 1 the outer radiosity is σT2⁴ exactly and only δ remains.
        const double e = double(report["energy"]["relative_error"]) * double(report["energy"]["absolute_power"]);
        const double k = (1.0 - e2) / e2;
        const double bound = e1 * ((jmax - jmin) + delta * jmax + k * e / a2) / (1.0 - e1 * k * a1 / a2) + 1e-8 * closed;
        EXPECT_NEAR(q1, closed, bound) << "row sums " << smin << ".." << smax << ", J2 " << jmin << ".." << jmax;
        // Measured (for docs/radiate.md): the relative error and the bound's.
        std::cout << "[measured] eps2 " << e2 << ": q1 " << q1 << " closed " << closed << " rel error "
                  << std::abs(q1 - closed) / closed << " bound " << bound / closed << "\n";
        // The two objects' powers cancel but for what leaks through the rows' sums (energy.sky: Σ A_i
        // (1 − s_i) J_i, to a sky at 0 K) and the balance error e; plus the CSV's 10 digits.
        const double p1 = column(read_text(dir / "q.csv"), "power").at("inner");
        const double p2 = column(read_text(dir / "q.csv"), "power").at("outer");
        EXPECT_NEAR(p1 + p2, 0.0, std::abs(double(report["energy"]["sky"])) + e + 1e-9 * std::abs(p1));
        if (e2 == 1.0) {
            // GR(inner, outer) = A1 / (1/ε1 + (A1/A2)(1/ε2 − 1)) = ε1 A1 at ε2 = 1. The written value is the mean
            // of GR_12 (outer's rows to the inner cube, so object reciprocity r enters) and GR_21 (inner's
            // rows: ε1 Σ A_i s_i): within ε1 A1 (δ + r).
            const double r_obj = report["reciprocity"]["object_max_rel"];
            const auto g = column(read_text(dir / "g.csv"), "GR");
            ASSERT_TRUE(g.count("inner")) << read_text(dir / "g.csv");
            EXPECT_NEAR(g.at("inner"), e1 * a1, e1 * a1 * (delta + r_obj) + 1e-9);
            EXPECT_LE(double(report["conductances"]["sum_rule_error"]), delta + r_obj + 1e-9);
        }
    }
}

TEST_F(RadiateCli, OpenPlateNeedsSkyTemperatureAndMatchesIt) {
    write_file(dir / "plate.obj", "o plate\nv 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf 1 2 3 4\n");
    write_file(dir / "s.csv", "object,emissivity,temperature,heat_flux\nplate,0.7,350,\n");
    const std::string base = "radiate " + (dir / "plate.obj") + " --no-subdivide -q --surfaces " + (dir / "s.csv") + " -o " + (dir / "q.csv");
    const RunResult refused = run_ffcube(base);
    EXPECT_EQ(refused.code, 2) << refused.output;
    EXPECT_NE(refused.output.find("100% of the hemisphere escapes"), std::string::npos) << refused.output;
    EXPECT_FALSE(std::filesystem::exists(dir / "q.csv"));
    const RunResult r = run_ffcube(base + " --sky-temperature 250");
    ASSERT_EQ(r.code, 0) << r.output;
    // The plate sees nothing (its row is empty, F_sky = 1 exactly): q = εσ(T⁴ − T_sky⁴) up to the
    // CSV's 10 significant digits.
    const double q = 0.7 * kSigma * (std::pow(350.0, 4) - std::pow(250.0, 4));
    EXPECT_NEAR(column(read_text(dir / "q.csv"), "heat_flux").at("plate"), q, 1e-9 * q);
}

TEST_F(RadiateCli, BadSurfacesAreRefusedNamingFileAndLine) {
    const std::string h = "object,emissivity,temperature,heat_flux\n";
    struct Bad {
        std::string csv, says;
    };
    for (const Bad& b : {Bad{h + "inner,0.5,300,\nouter,0,300,\n", "s.csv:3: emissivity 0"},
                         Bad{h + "inner,0.5,300,5\nouter,0.5,300,\n", "s.csv:2: 'inner' gives both"},
                         Bad{h + "inner,0.5,,\nouter,0.5,300,\n", "s.csv:2: 'inner' gives neither"},
                         Bad{h + "inner,0.5,abc,\nouter,0.5,300,\n", "s.csv:2: temperature 'abc'"},
                         Bad{h + "inner,0.5,300,\nouter,0.5,300,\nbox,0.5,300,\n", "s.csv:4: the scene has no object 'box'"},
                         Bad{h + "inner,0.5,300,\n", "object 'outer' of the scene is not listed"},
                         Bad{"inner,0.5,300,\n", "s.csv:1: the first line must be the header"}}) {
        write_file(dir / "s.csv", b.csv);
        const RunResult r = run_ffcube("radiate " + (dir / "box.obj") + " --no-subdivide -q --surfaces " + (dir / "s.csv") +
                                       " -o " + (dir / "q.csv") + " --report " + (dir / "r.json"));
        EXPECT_EQ(r.code, 2) << r.output;
        EXPECT_NE(r.output.find(b.says), std::string::npos) << r.output;
        EXPECT_FALSE(std::filesystem::exists(dir / "q.csv"));
        EXPECT_FALSE(std::filesystem::exists(dir / "r.json"));
    }
    // --default-surface fills the unlisted object.
    write_file(dir / "s.csv", h + "inner,0.5,300,\n");
    const RunResult ok = run_ffcube("radiate " + (dir / "box.obj") + " --no-subdivide -q --surfaces " + (dir / "s.csv") +
                                    " --default-surface 0.9,290 -o " + (dir / "q.csv"));
    EXPECT_EQ(ok.code, 0) << ok.output;
    EXPECT_DOUBLE_EQ(column(read_text(dir / "q.csv"), "temperature").at("outer"), 290.0);
}

TEST_F(RadiateCli, UnconvergedIsExit5WithoutResults) {
    write_file(dir / "s.csv", "object,emissivity,temperature,heat_flux\ninner,0.02,800,\nouter,0.02,,0\n");
    const RunResult r = run_ffcube("radiate " + (dir / "box.obj") + " --no-subdivide -q --surfaces " + (dir / "s.csv") +
                                   " -o " + (dir / "q.csv") + " --set max-iterations=2 --set gmres-restart=1 --report " +
                                   (dir / "r.json"));
    EXPECT_EQ(r.code, 5) << r.output;
    EXPECT_FALSE(std::filesystem::exists(dir / "q.csv"));
    ASSERT_TRUE(std::filesystem::exists(dir / "r.json"));
    EXPECT_FALSE(nlohmann::json::parse(read_text(dir / "r.json"))["converged"].get<bool>());
}

// --bands: one band over all wavelengths is the gray run byte for byte; bad bands are refused
// naming B.csv:LINE (exit 2, nothing written); an outer iteration stopped short is exit 5.
TEST_F(RadiateCli, BandsOneBandIsGrayAndBadBandsAreRefused) {
    write_file(dir / "s.csv", "object,emissivity,temperature,heat_flux\ninner,0.4,800,\nouter,0.6,,-100\n");
    // F once (every run below reads it): each run then costs milliseconds.
    ASSERT_EQ(run_ffcube("formfactors " + (dir / "box.obj") + " --no-subdivide -q -o " + (dir / "F.ffm")).code, 0);
    const std::string base = "radiate " + (dir / "box.obj") + " --no-subdivide -q --matrix " + (dir / "F.ffm") +
                             " --surfaces " + (dir / "s.csv");
    const std::string h = "object,lambda_min_um,lambda_max_um,emissivity\n";
    // One band over all wavelengths. 'outer' (a given heat flux) goes through the outer iteration,
    // stopped here at a flux residual r ≤ 1e-12 × σ(800 K)⁴ = 2.3e-8 W/m². Its σT⁴ then errs by
    // r / (dq2/de2), dq2/de2 = (A1/A2)/(1/ε1 + (A1/A2)(1/ε2 − 1)) = 0.0246 for the two-surface form
    // (A1/A2 = 1/16), i.e. ≤ 1e-6 W/m² of σT2⁴ ≈ 1.9e4: T relative ≤ 1.3e-11 (×10 for the form being
    // the box's approximation), plus the CSV's 10 digits (5e-10).
    write_file(dir / "b.csv", h + "inner,0,inf,0.4\nouter,0,inf,0.6\n");
    ASSERT_EQ(run_ffcube(base + " -o " + (dir / "gray.csv")).code, 0);
    const RunResult one =
        run_ffcube(base + " --bands " + (dir / "b.csv") + " --set outer-tolerance=1e-12 -o " + (dir / "one.csv"));
    ASSERT_EQ(one.code, 0) << one.output;
    const double tg = column(read_text(dir / "gray.csv"), "temperature").at("outer");
    const double tb = column(read_text(dir / "one.csv"), "temperature").at("outer");
    EXPECT_NEAR(tb, tg, (1.3e-10 + 1e-9) * tg);
    // The held inner cube's flux: the same to the CSV's digits and the solves' 1e-10.
    const double qg = column(read_text(dir / "gray.csv"), "heat_flux").at("inner");
    EXPECT_NEAR(column(read_text(dir / "one.csv"), "heat_flux").at("inner"), qg, 2e-9 * std::abs(qg));
    // Temperatures only: byte for byte.
    write_file(dir / "s2.csv", "object,emissivity,temperature,heat_flux\ninner,0.4,800,\nouter,0.6,300,\n");
    const std::string base2 = "radiate " + (dir / "box.obj") + " --no-subdivide -q --matrix " + (dir / "F.ffm") +
                              " --surfaces " + (dir / "s2.csv");
    ASSERT_EQ(run_ffcube(base2 + " -o " + (dir / "gray2.csv")).code, 0);
    ASSERT_EQ(run_ffcube(base2 + " --bands " + (dir / "b.csv") + " -o " + (dir / "one2.csv")).code, 0);
    EXPECT_EQ(read_text(dir / "one2.csv"), read_text(dir / "gray2.csv"));

    struct Bad {
        std::string csv, says;
        int code;
        std::string extra;
    };
    for (const Bad& b : {Bad{h + "inner,0,5,0.4\ninner,4,inf,0.3\n", "b.csv:3: band [4, inf] um of 'inner' overlaps", 2, ""},
                         Bad{h + "inner,6,5,0.4\n", "b.csv:2: band [6, 5] um of 'inner' is inverted", 2, ""},
                         Bad{h + "inner,0,5,0.4\nlid,0,5,0.4\n", "b.csv:3: the scene has no object 'lid'", 2, ""},
                         Bad{h + "inner,0,5,1.4\n", "b.csv:2: emissivity 1.4", 2, ""},
                         Bad{h + "inner,0,5,0.4\n", "--conductances with --bands", 2, " --conductances " + (dir / "g.csv")},
                         Bad{h + "inner,0,5,0.9\nouter,0,8,0.1\n", "did not converge in 1 outer iterations", 5,
                             " --set max-outer-iterations=1"}}) {
        write_file(dir / "b.csv", b.csv);
        const RunResult r = run_ffcube(base + " --bands " + (dir / "b.csv") + " -o " + (dir / "q.csv") + b.extra);
        EXPECT_EQ(r.code, b.code) << r.output;
        EXPECT_NE(r.output.find(b.says), std::string::npos) << r.output;
        EXPECT_FALSE(std::filesystem::exists(dir / "q.csv"));
    }
}

// --stream-matrix: F read block by block at every product gives the same bytes as F in memory
// (each row summed in the same order), for the fluxes, the patches and the conductances.
TEST_F(RadiateCli, StreamedMatrixGivesTheSameBytes) {
    write_file(dir / "s.csv", "object,emissivity,temperature,heat_flux\ninner,0.3,700,\nouter,0.05,,0\n");
    ASSERT_EQ(run_ffcube("formfactors " + (dir / "box.obj") + " --max-patch-edge 1 -q -o " + (dir / "F.ffm")).code, 0);
    const std::string base = "radiate " + (dir / "box.obj") + " --max-patch-edge 1 -q --matrix " + (dir / "F.ffm") +
                             " --sky-temperature 3 --surfaces " + (dir / "s.csv");
    for (const std::string tag : {"m", "s"}) {
        const RunResult r = run_ffcube(base + (tag == "s" ? " --set stream-matrix=true" : "") + " -o " + (dir / ("q" + tag)) +
                                       " --patch-out " + (dir / ("p" + tag)) + " --conductances " + (dir / ("g" + tag)));
        ASSERT_EQ(r.code, 0) << r.output;
    }
    for (const std::string f : {"q", "p", "g"}) EXPECT_EQ(read_text(dir / (f + "s")), read_text(dir / (f + "m"))) << f;
    const RunResult no_matrix = run_ffcube("radiate " + (dir / "box.obj") + " -q --surfaces " + (dir / "s.csv") +
                                           " --set stream-matrix=true -o " + (dir / "q.csv"));
    EXPECT_EQ(no_matrix.code, 2) << no_matrix.output;
    EXPECT_NE(no_matrix.output.find("--stream-matrix needs --matrix"), std::string::npos) << no_matrix.output;
    EXPECT_FALSE(std::filesystem::exists(dir / "q.csv"));
    // A .ffm made for another meshing of the scene: refused, in memory or streamed (exit 2, nothing written).
    for (const std::string stream : {"", " --set stream-matrix=true"}) {
        const RunResult other = run_ffcube("radiate " + (dir / "box.obj") + " --max-patch-edge 2 -q --matrix " +
                                           (dir / "F.ffm") + " --sky-temperature 3 --surfaces " + (dir / "s.csv") + stream +
                                           " -o " + (dir / "q.csv"));
        EXPECT_EQ(other.code, 2) << other.output;
        EXPECT_NE(other.output.find("was computed for a different scene or meshing"), std::string::npos) << other.output;
        EXPECT_FALSE(std::filesystem::exists(dir / "q.csv"));
    }
}

}  // namespace
}  // namespace ffcube::test
