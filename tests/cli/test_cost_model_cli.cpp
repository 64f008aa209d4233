// `ffcube calibrate` and `--cost-model FILE` (pipeline/cost_model.hpp, docs/accuracy.md "Cost
// model"): a measured model is written and read back; a model moves the automatic far-field
// choice the way its budget says; runs and checkpoints record it; bad files are refused by name.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <vector>
#include <nlohmann/json.hpp>

#include "cli/cli_util.hpp"
#include "ffcube/io/ffm.hpp"

namespace ffcube {
namespace {

using test::run_ffcube;
using test::TempDir;

void write(const std::string& path, const std::string& text) { std::ofstream(path) << text; }

nlohmann::json report_of(const std::string& path) { return nlohmann::json::parse(test::read_text(path)); }

TEST(CostModelCli, CalibrateWritesAModelThatRunsRead) {
    TempDir dir;
    const std::string model = dir / "costs.json";
    const auto c = run_ffcube("calibrate --patches 100 --resolution 32 --rows 8 -o " + model);
    ASSERT_EQ(c.code, 0) << c.output;
    const auto m = report_of(model);
    // The ranges read_cost_model accepts: a row of 3 × 32² pixels takes between 0.3 µs and 30 s.
    const double pixel_ns = m.at("pixel_ns").get<double>(), cpu_scale = m.at("cpu_scale").get<double>();
    EXPECT_TRUE(std::isfinite(pixel_ns) && pixel_ns >= 1e-4 && pixel_ns <= 1e4) << pixel_ns;
    EXPECT_TRUE(std::isfinite(cpu_scale) && cpu_scale >= 1e-3 && cpu_scale <= 1e3) << cpu_scale;
    // piece_ns and ray_ns within their ranges: a piece between 1 ps and 10 ms a hemicube, a ray
    // between 10 ps and 1 ms.
    const double piece_ns = m.at("piece_ns").get<double>(), ray_ns = m.at("ray_ns").get<double>();
    EXPECT_TRUE(std::isfinite(piece_ns) && piece_ns >= 1e-3 && piece_ns <= 1e7) << piece_ns;
    EXPECT_TRUE(std::isfinite(ray_ns) && ray_ns >= 1e-2 && ray_ns <= 1e6) << ray_ns;
    EXPECT_EQ(m.at("resolution").get<int>(), 32);
    EXPECT_NE(c.output.find("wrote " + model), std::string::npos) << c.output;

    // --method hemicube: the pixel model is the hemicube's (the report's cost_model.* keys). With
    // --method auto the measured costs choose the engine, and a run whose timings differ (under a
    // sanitizer, or a loaded machine) may price the rays cheaper and cast this cube instead;
    // MethodFollowsTheRowCosts checks that choice with fixed files.
    const auto r = run_ffcube("formfactors " + test::example("cube.obj") +
                              " --max-patch-edge 0.5 --resolution 32 --method hemicube -q --cost-model " + model +
                              " --report " + (dir / "r.json"));
    ASSERT_EQ(r.code, 0) << r.output;
    const auto rep = report_of(dir / "r.json");
    EXPECT_EQ(rep.at("cost_model").at("source").get<std::string>(), model);
    EXPECT_EQ(rep.at("cost_model").at("pixel_ns").get<double>(), pixel_ns);
    EXPECT_EQ(rep.at("cost_model").at("cpu_scale").get<double>(), cpu_scale);
}

// `--far-field auto` is on where the estimated CPU cost per row is at most the budget, 0.3 × 3N² ×
// pixel_ns / cpu_scale plus the rows it makes complete (accuracy/far_field.cpp). At N = 64:
// - parallel_squares.obj: estimated 0.076 ms per row; built-in budget 0.3 × 12,288 × 5 ns = 18 µs
//   plus a whole row (61 µs) for each row it completes, so on; at pixel_ns 0.001 the budget is
//   1000 × below the floor of 12 ns per patch (2,048 patches: 25 µs), so off.
// - boxed_blocker.obj: estimated 0.325 ms per row against the built-in 22 µs, so off; at pixel_ns
//   1000 the budget is 200 × larger (4.45 ms), so on.
TEST(CostModelCli, MovesTheFarFieldChoiceAsItsBudgetSays) {
    TempDir dir;
    write(dir / "fast.json", R"({"pixel_ns": 0.001, "cpu_scale": 1})");
    write(dir / "slow.json", R"({"pixel_ns": 1000, "cpu_scale": 1})");
    struct Case {
        const char* scene;
        std::string model;
        bool on;
    };
    for (const Case& k : {Case{"parallel_squares.obj", "", true}, Case{"parallel_squares.obj", dir / "fast.json", false},
                          Case{"boxed_blocker.obj", "", false}, Case{"boxed_blocker.obj", dir / "slow.json", true}}) {
        const std::string what = std::string(k.scene) + " " + k.model;
        // --method hemicube: the far field is the hemicube's (a slow pixel would otherwise move
        // --method auto to the rays, MethodFollowsTheRowCosts below).
        const auto r = run_ffcube("formfactors " + test::example(k.scene) + " --method hemicube --resolution 64 -q --report " + (dir / "r.json") +
                                  (k.model.empty() ? "" : " --cost-model " + k.model));
        ASSERT_EQ(r.code, 0) << what << r.output;
        const auto rep = report_of(dir / "r.json");
        const std::string status = rep.at("corrections").at("far_field").get<std::string>();
        EXPECT_EQ(status.rfind(k.on ? "on" : "off", 0), 0u) << what << ": " << status;
        EXPECT_EQ(rep.at("cost_model").at("source").get<std::string>(), k.model.empty() ? "built-in" : k.model) << what;
    }
}

// A file written before piece_ns and ray_ns (only pixel_ns and cpu_scale, as fast.json above) is
// read with the built-in values for them: its settings record 500 and 60.
TEST(CostModelCli, OldFilesReadWithTheBuiltInRowCosts) {
    TempDir dir;
    write(dir / "old.json", R"({"pixel_ns": 7, "cpu_scale": 1, "measured_on": "an older calibrate"})");
    const auto r = run_ffcube("formfactors " + test::example("parallel_squares.obj") + " --resolution 16 -q --cost-model " +
                              (dir / "old.json") + " -o " + (dir / "F.ffm"));
    ASSERT_EQ(r.code, 0) << r.output;
    EXPECT_NE(read_ffm(dir / "F.ffm").meta.settings.find("cost_model=7/1/500/60"), std::string::npos)
        << read_ffm(dir / "F.ffm").meta.settings;
}

// The model is part of how rows are made: a checkpoint made with one is not resumed without it.
TEST(CostModelCli, CheckpointsRecordTheModel) {
    TempDir dir;
    write(dir / "fast.json", R"({"pixel_ns": 0.001, "cpu_scale": 1})");
    const std::string base = "formfactors " + test::example("parallel_squares.obj") + " --resolution 32 -q --checkpoint " +
                             (dir / "ck") + " -o " + (dir / "F.ffm");
    ASSERT_EQ(run_ffcube(base + " --cost-model " + (dir / "fast.json")).code, 0);
    const auto again = run_ffcube(base + " --resume");
    EXPECT_EQ(again.code, 2) << again.output;
    EXPECT_NE(again.output.find("cost_model=0.001/1"), std::string::npos) << again.output;
    const auto same = run_ffcube(base + " --resume --cost-model " + (dir / "fast.json"));
    EXPECT_EQ(same.code, 0) << same.output;
}

// The error_estimate column of a --patch-table CSV, by patch.
std::vector<double> estimates_of(const std::string& path) {
    std::istringstream in(test::read_text(path));
    std::string line;
    std::getline(in, line);  // header; error_estimate is the last column
    std::vector<double> e;
    while (std::getline(in, line)) e.push_back(std::stod(line.substr(line.rfind(',') + 1)));
    return e;
}

// --method auto by the costs of a --cost-model file (pipeline/row_engine.hpp): cheap pixels (a
// GPU-like 0.01 ns, 10 ns a piece) make a 300-facet city, which the built-in model casts, drawn:
// 16 × (3 × 32² × 0.01 + 300 × 10) ns = 0.048 ms a row of 4 × 4 sub-hemicubes against 8,192 rays
// (E = 1e-2's budget) × 60 ns = 0.49 ms. The report says so with both costs; the drawn rows agree
// with the ray caster's refined to 2e-3 within the sum of the two rows' own estimates (the
// tolerance's promise: at least 95% of rows within their estimate, none beyond 3 times it;
// docs/accuracy.md, "Accuracy by target"), compared on each row's sum (1 − its sky view factor).
TEST(CostModelCli, MethodFollowsTheRowCosts) {
    TempDir dir;
    const std::string city = dir / "city.stl";
    ASSERT_EQ(test::gen_city(city, 300, 1), 0);
    write(dir / "gpu.json", R"({"pixel_ns": 0.01, "cpu_scale": 1, "piece_ns": 10, "ray_ns": 60})");
    const std::string base = "formfactors " + city + " --no-subdivide --resolution 32 -q";
    const auto g = run_ffcube(base + " --tolerance 1e-2 --cost-model " + (dir / "gpu.json") + " -o " + (dir / "g.ffm") +
                              " --report " + (dir / "g.json") + " --patch-table " + (dir / "g.csv"));
    ASSERT_EQ(g.code, 0) << g.output;
    const auto rep = report_of(dir / "g.json");
    EXPECT_EQ(rep.at("method").get<std::string>(), "hemicube");
    const auto& mc = rep.at("method_cost");
    EXPECT_EQ(mc.at("rows_4x4").get<std::string>(), "hemicube");
    EXPECT_NEAR(mc.at("scene_row_hemicube_ms").get<double>(), 16 * (3 * 32 * 32 * 0.01 + 300 * 10) * 1e-6, 1e-12);
    EXPECT_NEAR(mc.at("scene_row_rays_ms").get<double>(), 8192 * 60 * 1e-6, 1e-12);
    EXPECT_NE(read_ffm(dir / "g.ffm").meta.settings.find("cost_model=0.01/1/10/60"), std::string::npos);
    // The built-in model: the same city by rays (the piece-count rule).
    const auto b = run_ffcube(base + " --tolerance 1e-2 --report " + (dir / "b.json"));
    ASSERT_EQ(b.code, 0) << b.output;
    EXPECT_EQ(report_of(dir / "b.json").at("method").get<std::string>(), "raycast");

    const auto r = run_ffcube(base + " --method raycast --tolerance 2e-3 -o " + (dir / "r.ffm") + " --patch-table " +
                              (dir / "r.csv"));
    ASSERT_EQ(r.code, 0) << r.output;
    const FfmFile drawn = read_ffm(dir / "g.ffm"), cast = read_ffm(dir / "r.ffm");
    const std::vector<double> eg = estimates_of(dir / "g.csv"), er = estimates_of(dir / "r.csv");
    ASSERT_EQ(drawn.matrix.size(), 300u);
    ASSERT_EQ(cast.matrix.size(), 300u);
    ASSERT_EQ(eg.size(), 300u);
    ASSERT_EQ(er.size(), 300u);
    std::size_t within = 0;
    double worst = 0;
    for (std::uint32_t i = 0; i < 300; ++i) {
        const double d = std::abs(drawn.matrix.row(i).sum() - cast.matrix.row(i).sum()), bound = eg[i] + er[i];
        within += d <= bound;
        worst = std::max(worst, d / bound);
    }
    EXPECT_GE(within, 285u) << "rows within the sum of their estimates (95% of 300)";
    EXPECT_LE(worst, 3.0);
}

TEST(CostModelCli, BadFilesAreRefusedByName) {
    TempDir dir;
    struct Case {
        const char* name;
        const char* text;  // null: no file
        const char* says;
    };
    for (const Case& k : {Case{"missing.json", nullptr, "cannot read the cost model: no such file"}, Case{"text.json", "pixel_ns = 5", "not JSON"},
                          Case{"array.json", "[5, 1]", "not a JSON object"},
                          Case{"nokey.json", R"({"pixel_ns": 5})", "\"cpu_scale\" is missing"},
                          Case{"word.json", R"({"pixel_ns": "fast", "cpu_scale": 1})", "\"pixel_ns\" is not a number"},
                          Case{"zero.json", R"({"pixel_ns": 0, "cpu_scale": 1})", "pixel_ns 0 is outside"},
                          Case{"huge.json", R"({"pixel_ns": 5, "cpu_scale": 1e9})", "cpu_scale 1000000000 is outside"},
                          Case{"piece.json", R"({"pixel_ns": 5, "cpu_scale": 1, "piece_ns": -1})", "piece_ns -1 is outside"},
                          Case{"ray.json", R"({"pixel_ns": 5, "cpu_scale": 1, "ray_ns": "slow"})", "\"ray_ns\" is not a number"},
                          Case{"rayzero.json", R"({"pixel_ns": 5, "cpu_scale": 1, "ray_ns": 0})", "ray_ns 0 is outside"}}) {
        const std::string path = dir / k.name;
        if (k.text) write(path, k.text);
        const auto r = run_ffcube("formfactors " + test::example("cube.obj") + " --resolution 32 -q -o " + (dir / "F.ffm") +
                                  " --cost-model " + path);
        EXPECT_EQ(r.code, 2) << k.name << ": " << r.output;
        EXPECT_NE(r.output.find(path), std::string::npos) << k.name << ": " << r.output;
        EXPECT_NE(r.output.find(k.says), std::string::npos) << k.name << ": " << r.output;
        EXPECT_FALSE(std::filesystem::exists(dir / "F.ffm")) << k.name;
    }
    const auto c = run_ffcube("calibrate --patches 100");
    EXPECT_EQ(c.code, 2) << c.output;  // -o is required
}

}  // namespace
}  // namespace ffcube
