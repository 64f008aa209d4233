// `ffcube calibrate` and `--cost-model FILE` (pipeline/cost_model.hpp, docs/accuracy.md "Cost
// model"): a measured model is written and read back; a model moves the automatic far-field
// choice the way its budget says; runs and checkpoints record it; bad files are refused by name.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>

#include "cli/cli_util.hpp"

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
    EXPECT_EQ(m.at("resolution").get<int>(), 32);
    EXPECT_NE(c.output.find("wrote " + model), std::string::npos) << c.output;

    const auto r = run_ffcube("formfactors " + test::example("cube.obj") + " --max-patch-edge 0.5 --resolution 32 -q --cost-model " +
                              model + " --report " + (dir / "r.json"));
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
        const auto r = run_ffcube("formfactors " + test::example(k.scene) + " --resolution 64 -q --report " + (dir / "r.json") +
                                  (k.model.empty() ? "" : " --cost-model " + k.model));
        ASSERT_EQ(r.code, 0) << what << r.output;
        const auto rep = report_of(dir / "r.json");
        const std::string status = rep.at("corrections").at("far_field").get<std::string>();
        EXPECT_EQ(status.rfind(k.on ? "on" : "off", 0), 0u) << what << ": " << status;
        EXPECT_EQ(rep.at("cost_model").at("source").get<std::string>(), k.model.empty() ? "built-in" : k.model) << what;
    }
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
                          Case{"huge.json", R"({"pixel_ns": 5, "cpu_scale": 1e9})", "cpu_scale 1000000000 is outside"}}) {
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
