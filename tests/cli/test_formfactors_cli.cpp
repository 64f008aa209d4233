// The `ffcube formfactors` command end to end: outputs agree with each other, runs are
// reproducible, bad input is refused with a message, a non-zero exit and no output file.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>
#include <nlohmann/json.hpp>

#include "cli/cli_util.hpp"
#include "ffcube/formfactor/checks.hpp"
#include "ffcube/io/ffm.hpp"

namespace ffcube {
namespace {

using test::run_ffcube;
using test::TempDir;

std::map<std::pair<std::string, std::string>, double> read_groups(const std::string& path) {
    std::map<std::pair<std::string, std::string>, double> g;
    std::istringstream in(test::read_text(path));
    std::string line;
    std::getline(in, line);
    EXPECT_EQ(line, "from,to,F");
    while (std::getline(in, line)) {
        const auto c1 = line.find(','), c2 = line.rfind(',');
        g[{line.substr(0, c1), line.substr(c1 + 1, c2 - c1 - 1)}] = std::stod(line.substr(c2 + 1));
    }
    return g;
}

TEST(FormfactorsCli, OutputsAgreeAndReportIsComplete) {
    TempDir dir;
    const auto r = run_ffcube("formfactors " + test::example("cube.obj") + " --max-patch-edge 0.25 --resolution 64 -q" +
                              " -o " + (dir / "F.ffm") + " --groups " + (dir / "g.csv") + " --report " + (dir / "r.json"));
    ASSERT_EQ(r.code, 0) << r.output;
    const FfmFile f = read_ffm(dir / "F.ffm");
    EXPECT_EQ(f.matrix.size(), 96u);  // 6 faces × 4 × 4
    // The groups CSV is the object-level reduction of the matrix (printed with 9 digits).
    const auto groups = read_groups(dir / "g.csv");
    std::vector<double> area(f.object_names.size(), 0.0);
    std::vector<std::vector<double>> G(area.size(), std::vector<double>(area.size(), 0.0));
    for (std::uint32_t i = 0; i < f.matrix.size(); ++i) {
        area[f.objects[i]] += f.areas[i];
        const RowView row = f.matrix.row(i);
        for (std::size_t k = 0; k < row.col.size(); ++k) G[f.objects[i]][f.objects[row.col[k]]] += f.areas[i] * row.val[k];
    }
    EXPECT_EQ(groups.size(), 30u);  // closed cube: every ordered pair of walls sees each other
    for (const auto& [key, value] : groups) {
        std::size_t a = 0, b = 0;
        while (f.object_names[a] != key.first) ++a;
        while (f.object_names[b] != key.second) ++b;
        EXPECT_NEAR(value, G[a][b] / area[a], 1e-8) << key.first << "->" << key.second;
    }
    const auto report = nlohmann::json::parse(test::read_text(dir / "r.json"));
    for (const char* key : {"patches", "hemicubes", "seconds", "backend", "renderer", "resolution", "row_sums", "reciprocity",
                            "time", "left_out"})
        EXPECT_TRUE(report.contains(key)) << key;
    EXPECT_EQ(report["patches"], 96);
    // Every row is rendered or, known wholly from analytic values (a closed box: nothing blocks,
    // so by default no hemicube at all), not rendered.
    EXPECT_EQ(report["hemicubes"].get<int>() + report["rows_not_rendered"].get<int>(), 96);
    EXPECT_EQ(report["resolution"], 64);
    // Rates: rows (patches) and hemicubes drawn, each over the run's seconds (the same double
    // division, so equal up to the JSON's 17 digits).
    const double seconds = report["seconds"].get<double>();
    EXPECT_DOUBLE_EQ(report["rows_per_second"].get<double>(), 96.0 / std::max(seconds, 1e-9));
    EXPECT_DOUBLE_EQ(report["hemicubes_per_second"].get<double>(), report["hemicubes"].get<double>() / std::max(seconds, 1e-9));
    EXPECT_TRUE(report["upload"].contains("vertex_bytes"));
    // Closed cube: rows sum to 1 up to float storage (2^-24 per entry).
    EXPECT_NEAR(report["row_sums"]["min"].get<double>(), 1.0, 1e-6);
    for (const char* key : {"meshing", "drawing", "readback", "accumulation", "writing"})
        EXPECT_TRUE(report["time"].contains(key)) << key;
}

TEST(FormfactorsCli, MatrixMarketReadableByScipy) {
    if (std::system("/usr/bin/python3 -c 'import scipy.io' 2>/dev/null") != 0) GTEST_SKIP() << "no python3-scipy";
    TempDir dir;
    ASSERT_EQ(run_ffcube("formfactors " + test::example("parallel_squares.obj") +
                         " --max-patch-edge 0.5 --resolution 32 -q -o " + (dir / "F.mtx") + " --report " + (dir / "r.json"))
                  .code,
              0);
    const auto report = nlohmann::json::parse(test::read_text(dir / "r.json"));
    // scipy's row sums must reproduce the report's row sums (same matrix, 9 printed digits).
    const std::string py = "import scipy.io,numpy; m=scipy.io.mmread('" + (dir / "F.mtx") +
                           "').tocsr(); s=numpy.asarray(m.sum(axis=1)).ravel(); print(m.shape[0], m.nnz, s.min(), s.max())";
    FILE* p = popen(("/usr/bin/python3 -c \"" + py + "\"").c_str(), "r");
    ASSERT_NE(p, nullptr);
    int n = 0;
    long nnz = 0;
    double mn = 0, mx = 0;
    ASSERT_EQ(std::fscanf(p, "%d %ld %lf %lf", &n, &nnz, &mn, &mx), 4);
    pclose(p);
    EXPECT_EQ(n, report["patches"].get<int>());
    EXPECT_EQ(nnz, report["nnz"].get<long>());
    EXPECT_NEAR(mn, report["row_sums"]["min"].get<double>(), 1e-7);
    EXPECT_NEAR(mx, report["row_sums"]["max"].get<double>(), 1e-7);
}

TEST(FormfactorsCli, ByteIdenticalAcrossRunsAndThreadCounts) {
    TempDir dir;
    // Default settings, and with the far field forced on (its analyses run on the provider's
    // threads, in whatever order rows come).
    for (const std::string extra : {"", " --far-field on"}) {
        const std::string base =
            "formfactors " + test::example("cube.obj") + " --max-patch-edge 0.2 --resolution 32 -q" + extra + " -o ";
        ASSERT_EQ(run_ffcube(base + (dir / "a.ffm") + " --threads 1").code, 0);
        ASSERT_EQ(run_ffcube(base + (dir / "b.ffm") + " --threads 2").code, 0);
        ASSERT_EQ(run_ffcube(base + (dir / "c.ffm") + " --threads 2").code, 0);
        const std::string a = test::read_text(dir / "a.ffm");
        EXPECT_FALSE(a.empty());
        EXPECT_EQ(a, test::read_text(dir / "b.ffm")) << extra;
        EXPECT_EQ(a, test::read_text(dir / "c.ffm")) << extra;
    }
}

// The report's coverage figures (the hemicubes' miss and back-face weights) are sums over every
// hemicube, merged across worker threads and processes in whatever order rows finish; they are
// summed as integers (HemicubeStats::kWeightUnit), so the report is the same whatever the thread
// count. Two plates (examples/parallel_squares.obj) leave most of each hemicube empty.
TEST(FormfactorsCli, CoverageFiguresDoNotDependOnTheThreadCount) {
    TempDir dir;
    const std::string base = "formfactors " + test::example("parallel_squares.obj") +
                             " --max-patch-edge 0.1 --method hemicube --resolution 32 -q -o " + (dir / "F.ffm") + " --report ";
    std::vector<double> miss;
    for (const std::string threads : {"1", "2", "2"}) {
        const std::string report = dir / ("r" + std::to_string(miss.size()) + ".json");
        ASSERT_EQ(run_ffcube(base + report + " --threads " + threads).code, 0);
        const auto r = nlohmann::json::parse(test::read_text(report));
        miss.push_back(r["coverage"]["mean_miss_fraction"].get<double>());
    }
    EXPECT_GT(miss[0], 0.5);  // each plate sees the other under F = 0.2: most pixels see nothing
    EXPECT_EQ(miss[0], miss[1]);
    EXPECT_EQ(miss[0], miss[2]);
}

struct BadCase {
    std::string args;
    int code;
    std::string message;
};

// --fine-rows: on a 1,200-facet city (a mesh of 1,000 pieces or more) hemicube runs ray-cast the
// rows planned at 4 × 4 by default and say so in their log and report; --fine-rows hemicubes
// draws them.
// The plans are the scene's, so both runs have the same rows at 4 × 4, and every other row is
// the same bits in both (.mtx text per row); a bad word is refused without output.
TEST(FormfactorsCli, FineRowsByRaysOnAMeshOfManyFacetsAndOnlyThoseRowsChange) {
    TempDir dir;
    const std::string city = dir / "city.stl";
    ASSERT_EQ(test::gen_city(city, 1200, 2), 0);
    std::map<std::string, nlohmann::json> report;
    std::map<std::string, std::map<std::string, std::string>> rows;  // run -> row -> its .mtx lines
    for (const std::string mode : {"auto", "hemicubes"}) {
        const std::string args = mode == "auto" ? "" : " --fine-rows " + mode;
        const auto r = run_ffcube("formfactors " + city + " --no-subdivide --method hemicube --resolution 32" + args +
                                  " -o " + (dir / (mode + ".mtx")) + " --report " + (dir / (mode + ".json")));
        ASSERT_EQ(r.code, 0) << r.output;
        EXPECT_EQ(r.output.find("ray-cast, 2048 rays each") != std::string::npos, mode == "auto") << r.output;
        report[mode] = nlohmann::json::parse(test::read_text(dir / (mode + ".json")));
        std::istringstream mtx(test::read_text(dir / (mode + ".mtx")));
        std::string line;
        bool size_line = true;
        while (std::getline(mtx, line)) {
            if (line.empty() || line[0] == '%') continue;
            if (size_line) {
                size_line = false;
                continue;
            }
            rows[mode][line.substr(0, line.find(' '))] += line + "\n";
        }
    }
    const auto& a = report["auto"];
    const auto& h = report["hemicubes"];
    EXPECT_EQ(a["fine_rows"]["by"], "rays");
    EXPECT_EQ(h["fine_rows"]["by"], "hemicubes");
    const std::uint64_t fine = a["corrections"]["rows_sub_hemicubes_4x4"].get<std::uint64_t>();
    EXPECT_GT(fine, 0u);
    EXPECT_EQ(a["fine_rows"]["cast"].get<std::uint64_t>(), fine);
    EXPECT_EQ(h["fine_rows"]["cast"].get<std::uint64_t>(), 0u);
    EXPECT_EQ(h["corrections"]["rows_sub_hemicubes_4x4"].get<std::uint64_t>(), fine);
    EXPECT_LT(a["hemicubes"].get<std::uint64_t>(), h["hemicubes"].get<std::uint64_t>());
    const auto measure = a["corrections"]["row_measure"];
    ASSERT_EQ(measure, h["corrections"]["row_measure"]);
    std::size_t same = 0, differ = 0;
    for (std::size_t i = 0; i < measure.size(); ++i) {
        const std::string key = std::to_string(i + 1);  // Matrix Market rows count from 1
        if (measure[i].get<int>() == 4) {
            differ += rows["auto"][key] != rows["hemicubes"][key];
        } else {
            EXPECT_EQ(rows["auto"][key], rows["hemicubes"][key]) << "row " << i << " (measure " << measure[i] << ")";
            ++same;
        }
    }
    EXPECT_GT(same, 0u);
    EXPECT_GT(differ, 0u);
    const auto bad = run_ffcube("formfactors " + city + " --no-subdivide --fine-rows maybe -o " + (dir / "x.ffm"));
    EXPECT_EQ(bad.code, 2) << bad.output;
    EXPECT_NE(bad.output.find("--fine-rows"), std::string::npos) << bad.output;
    EXPECT_FALSE(std::filesystem::exists(dir / "x.ffm"));
}

// --method auto (the default): a mesh of 1,000 pieces or more (the 1,200-facet city) gets the
// ray caster at the fine-row count for its resolution (2,048 at N = 32), the same bytes as that
// run named; --fine-rows hemicubes, or a scene of few pieces of many patches (the built-in box),
// the hemicube.
// The log and the report say which and why; a bad word is refused without output.
TEST(FormfactorsCli, MethodAutoCastsRaysOnAMeshOfManyFacets) {
    TempDir dir;
    const std::string city = dir / "city.stl";
    ASSERT_EQ(test::gen_city(city, 1200, 2), 0);
    // A loose target keeps the rows cheap (4,096 to 32,768 rays each): what is tested is the choice.
    const std::string base = "formfactors " + city + " --no-subdivide --resolution 32 --threads 2 --tolerance 1e-2";
    const auto a = run_ffcube(base + " -o " + (dir / "auto.ffm") + " --report " + (dir / "auto.json"));
    ASSERT_EQ(a.code, 0) << a.output;
    EXPECT_NE(a.output.find("rays per patch until each row is within --tolerance 0.01 (--method auto"), std::string::npos)
        << a.output;
    const auto named = run_ffcube(base + " --method raycast -o " + (dir / "named.ffm"));
    ASSERT_EQ(named.code, 0) << named.output;
    EXPECT_EQ(test::read_text(dir / "auto.ffm"), test::read_text(dir / "named.ffm"));
    const auto ra = nlohmann::json::parse(test::read_text(dir / "auto.json"));
    EXPECT_EQ(ra["method"], "raycast");
    EXPECT_EQ(ra["method_choice"], "auto: 1200 pieces, 1000 or more");
    // The rays keep near pairs provably below --near-min-ff (0.03) as cast, and say so; 0 tries
    // every near pair: the same pairs in all, the ones left out now examined.
    EXPECT_NE(a.output.find("keep their ray estimate (--near-min-ff)"), std::string::npos) << a.output;
    const auto all = run_ffcube(base + " --near-min-ff 0 -q -o " + (dir / "all.ffm") + " --report " + (dir / "all.json"));
    ASSERT_EQ(all.code, 0) << all.output;
    const auto rall = nlohmann::json::parse(test::read_text(dir / "all.json"));
    const auto below = ra["corrections"]["near_pairs_below_value"].get<std::uint64_t>();
    EXPECT_GT(below, 0u);
    EXPECT_EQ(rall["corrections"]["near_pairs_below_value"].get<std::uint64_t>(), 0u);
    EXPECT_EQ(rall["corrections"]["near_pairs"].get<std::uint64_t>(),
              ra["corrections"]["near_pairs"].get<std::uint64_t>() + below);
    EXPECT_GT(rall["corrections"]["entries_replaced"].get<std::uint64_t>(),
              ra["corrections"]["entries_replaced"].get<std::uint64_t>());

    const auto h = run_ffcube(base + " --fine-rows hemicubes -o " + (dir / "h.ffm") + " --report " + (dir / "h.json"));
    ASSERT_EQ(h.code, 0) << h.output;
    const auto rh = nlohmann::json::parse(test::read_text(dir / "h.json"));
    EXPECT_EQ(rh["method"], "hemicube");
    EXPECT_EQ(rh["method_choice"], "auto: 1200 pieces, --fine-rows hemicubes");

    const auto box = run_ffcube("formfactors --resolution 32 -q -o " + (dir / "box.ffm") + " --report " + (dir / "box.json"));
    ASSERT_EQ(box.code, 0) << box.output;
    const auto rb = nlohmann::json::parse(test::read_text(dir / "box.json"));
    EXPECT_EQ(rb["method"], "hemicube");
    EXPECT_NE(rb["method_choice"].get<std::string>().find("rays need 1000 pieces"), std::string::npos)
        << rb["method_choice"];

    const auto bad = run_ffcube(base + " --method maybe -o " + (dir / "x.ffm"));
    EXPECT_EQ(bad.code, 2) << bad.output;
    EXPECT_NE(bad.output.find("--method"), std::string::npos) << bad.output;
    EXPECT_FALSE(std::filesystem::exists(dir / "x.ffm"));
}

TEST(FormfactorsCli, BadInvocationsAreRefusedWithoutOutput) {
    TempDir dir;
    const std::string out = dir / "F.ffm";
    const std::string missing = dir / "no such.obj";
    const std::vector<BadCase> cases = {
        {"formfactors \"" + missing + "\" -o " + out, 2, "no such.obj"},
        {"formfactors " + dir.path().string() + " -o " + out, 2, "directory"},
        {"formfactors -o " + (dir / "F.txt"), 2, "must end in .ffm"},
        {"formfactors -o " + (dir / "nodir/F.ffm"), 2, "does not exist"},
        {"formfactors --resolution 7 -o " + out, 2, "even number"},
        {"formfactors --backend vulkan -o " + out, 2, "vulkan"},
        {"formfactors --objects-by groups -o " + out, 2, "--objects-by"},
        {"formfactors --patches 10 --max-patch-edge 1 -o " + out, 2, "excludes"},
        {"formfactors --max-patch-edge 1e-9 -o " + out, 2, "patches"},
        {"formfactors --near-min-ff 2 -o " + out, 2, "--near-min-ff"},
    };
    for (const auto& c : cases) {
        const auto r = run_ffcube(c.args);
        EXPECT_EQ(r.code, c.code) << c.args << "\n" << r.output;
        EXPECT_NE(r.output.find(c.message), std::string::npos) << c.args << "\n" << r.output;
        EXPECT_FALSE(std::filesystem::exists(out)) << c.args;
    }
    // Nothing but the (absent) outputs was left behind: no temporaries either.
    EXPECT_TRUE(std::filesystem::is_empty(dir.path()));
}

// Issue 13: a Cornell-box-like file that lists each block's faces before its 'g' line (one
// material per block). By groups (auto: the file has no 'o') the faces land in the object named
// before them; --objects-by material puts each block's faces together.
TEST(FormfactorsCli, ObjectsByMaterialGroupsFacesListedBeforeTheirG) {
    TempDir dir;
    const std::string obj = dir / "blocks.obj";
    // Two unit squares facing each other at distance 1 (F = 0.19982 each way), written as
    //   usemtl lower / f (lower) / g lower_block / usemtl upper / f (upper) / g upper_block
    std::ofstream(obj) << "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 0 0 1\nv 1 0 1\nv 1 1 1\nv 0 1 1\n"
                          "usemtl lower\nf 1 2 3 4\ng lower_block\nusemtl upper\nf 5 8 7 6\ng upper_block\n";
    const auto groups_of = [&](const std::string& by) {
        const std::string csv = dir / ("g_" + by + ".csv");
        const auto r = run_ffcube("formfactors " + obj + " --objects-by " + by +
                                  " --max-patch-edge 1 --resolution 64 --threads 1 -q --groups " + csv);
        EXPECT_EQ(r.code, 0) << r.output;
        return read_groups(csv);
    };
    const auto by_material = groups_of("material");
    ASSERT_EQ(by_material.size(), 2u);
    EXPECT_NEAR((by_material.at({"lower", "upper"})), 0.19982, 1e-3);
    EXPECT_NEAR((by_material.at({"upper", "lower"})), 0.19982, 1e-3);
    // auto and g: the lower square is "default" (no 'g' before it), the upper one "lower_block".
    for (const std::string by : {"auto", "g"}) {
        const auto g = groups_of(by);
        ASSERT_EQ(g.size(), 2u) << by;
        EXPECT_EQ(g.count({"default", "lower_block"}), 1u) << by;
    }
}

// With EGL's vendor list pointing nowhere, --backend egl has no context to offer: exit 4 and a
// message listing every EGL platform tried and why it failed; auto still falls back to OSMesa.
TEST(FormfactorsCli, NoBackendListsEveryAttempt) {
    TempDir dir;
    const std::string env = "__EGL_VENDOR_LIBRARY_FILENAMES=/nonexistent.json ";
    const std::string cmd = "formfactors " + test::example("parallel_squares.obj") + " --resolution 16 -q -o " + (dir / "F.ffm");
    const auto egl = test::run_ffcube_env(env, cmd + " --backend egl");
    EXPECT_EQ(egl.code, 4) << egl.output;
    EXPECT_NE(egl.output.find("no OpenGL 4.5 core context"), std::string::npos) << egl.output;
    EXPECT_NE(egl.output.find("egl device platform"), std::string::npos) << egl.output;
    EXPECT_NE(egl.output.find("egl surfaceless"), std::string::npos) << egl.output;
    EXPECT_FALSE(std::filesystem::exists(dir / "F.ffm"));
    const auto fallback = test::run_ffcube_env(env, cmd + " --report " + (dir / "r.json"));
    ASSERT_EQ(fallback.code, 0) << fallback.output;
    EXPECT_EQ(nlohmann::json::parse(test::read_text(dir / "r.json"))["backend"], "osmesa");
}

}  // namespace
}  // namespace ffcube
