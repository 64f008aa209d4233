// ffcube view: the interactive viewer of converging radiosity (docs/viewer.md). Thin: the
// options go to run_viewer in the viewer layer.
#include <fmt/format.h>

#include <charconv>
#include <cmath>
#include <tuple>

#include "cli/commands.hpp"
#include "cli/common.hpp"
#include "cli/expert.hpp"
#include "ffcube/core/error.hpp"
#include "ffcube/core/log.hpp"
#include "ffcube/pipeline/adaptive.hpp"
#include "ffcube/pipeline/row_source.hpp"
#include "ffcube/pipeline/scene_loading.hpp"
#include "ffcube/pipeline/solve.hpp"
#include "ffcube/viewer/viewer.hpp"

namespace ffcube::cli {
namespace {

struct Options {
    SceneFlags scene;
    AdaptiveFlags adaptive;  // --target-error, --max-elements: as solve
    RowOptions rows;
    SolverOptions solver;
    ViewerOptions viewer;
    std::string size = "1280x800", pick, objects;
    double exposure = NAN;
    std::uint32_t batch = kShotBatch;  // as solve
    bool no_ambient = false;
};

// "A<sep>B" with two non-negative integers, else InputError naming the option.
std::pair<int, int> parse_pair(const std::string& option, const std::string& text, char sep) {
    const auto at = text.find(sep);
    std::pair<int, int> v{-1, -1};
    const char* end = text.data() + text.size();
    const bool ok = at != std::string::npos &&
                    std::from_chars(text.data(), text.data() + at, v.first).ptr == text.data() + at &&
                    std::from_chars(text.data() + at + 1, end, v.second).ptr == end && v.first >= 0 && v.second >= 0;
    if (!ok) throw InputError(fmt::format("{} {}: expected two whole numbers as A{}B", option, text, sep));
    return v;
}

// The adaptive levels as the viewer shows them: each level's solve is the viewer's own progressive
// shooting; AdaptiveRun estimates, refines and re-points the hemicube workers in between.
class AdaptiveLevels final : public ViewerLevels {
public:
    explicit AdaptiveLevels(AdaptiveRun& run) : run_(run) {}
    const Scene& scene() const override { return run_.scene(); }
    RowProvider& provider() override { return run_.provider(); }
    HemicubeRowProvider* hemicube() override { return run_.hemicube(); }
    std::span<const std::uint32_t> origin() const override { return run_.origin(); }
    std::uint32_t level() const override { return run_.level(); }
    bool finish(const SolveResult& result) override {
        run_.finish_level(result);
        return !run_.done();
    }
    void advance() override { run_.next_level(); }

private:
    AdaptiveRun& run_;
};

void run_adaptive(const Options& o, const Scene& scene) {
    // The first level's row source is made here, before the window: its hemicube workers fork
    // while this process has no GL context, and every later level re-points them (nothing forks).
    AdaptiveRun run(scene, o.rows, front_end_solver_options(o.solver), o.adaptive.options,
                    [](const std::string& line) { info("{}", line); });
    for (const std::string& line : describe(run.rows())) info("{}", line);
    AdaptiveLevels levels(run);
    const SolveResult shown = run_viewer(levels, o.solver, o.viewer);
    // The level shown last: the last level, or the one whose solve the closed window interrupted.
    if (!o.objects.empty()) write_objects_csv(o.objects, run.scene(), shown.radiosity);
    if (!run.done()) return;
    const AdaptiveResult refined = run.take_result();
    info("adaptive: {} ({} elements from {} patches), largest estimated object error {:.3g}", refined.stop,
         refined.scene->size(), scene.size(), refined.max_relative_error);
}

int run(Options& o) {
    std::tie(o.viewer.width, o.viewer.height) = parse_pair("--size", o.size, 'x');
    if (!o.pick.empty()) o.viewer.pick = parse_pair("--pick", o.pick, ',');
    if (!std::isnan(o.exposure)) o.viewer.exposure = o.exposure;
    o.viewer.ambient = !o.no_ambient;
    o.solver.method = SolverMethod::Shoot;
    if (o.batch == 0) throw InputError("--batch 0: must be at least 1 shooter per call");
    o.solver.batch = o.batch;
    validate(o.solver);
    validate(o.viewer);
    check_output_path("--screenshot", o.viewer.screenshot);
    check_output_path("--exr", o.viewer.exr);
    check_output_path("--objects", o.objects);
    validate(o.rows);

    SceneOptions scene_options = o.scene.scene;
    prepare_adaptive(o.adaptive, scene_options);

    Report report;
    const Scene scene = load_and_mesh(scene_options, report);
    if (o.adaptive.on()) {
        run_adaptive(o, scene);
        return 0;
    }
    // Before the window: with no GL context in this process yet, the provider can fork its
    // workers (each with its own headless context) instead of sharing one process's llvmpipe.
    RowSource rows = make_row_source(scene, o.rows);
    for (const std::string& line : describe(rows)) info("{}", line);
    const SolveResult shown = run_viewer(scene, rows.provider(), rows.hemicube(), o.solver, o.viewer);
    if (!o.objects.empty()) write_objects_csv(o.objects, scene, shown.radiosity);
    return 0;
}

}  // namespace

void add_view_command(CLI::App& app, std::function<int()>& action) {
    auto opts = std::make_shared<Options>();
    CLI::App* sub = app.add_subcommand("view", "watch progressive radiosity converge in a window (docs/viewer.md)");
    add_scene_options(*sub, opts->scene);
    add_row_options(*sub, opts->rows, RowTolerance::expert);
    add_far_field_emitters_option(*sub, opts->rows);  // the same rows as solve's
    add_adaptive_options(*sub, opts->adaptive);
    auto& s = opts->solver;
    sub->add_option("--tolerance", s.tolerance, "stop shooting when unshot power <= tolerance x emitted power")
        ->default_val(s.tolerance);
    expert(sub->add_option("--max-shots", s.max_iterations, "stop after this many shots (0: 1000 per patch, at least 100000)"));
    expert(sub->add_option("--overshoot", s.overshoot, "over-relaxation factor w in [1, 2) (1: classic shooting)")
        ->default_val(s.overshoot));
    expert(sub->add_option("--row-cache-mb", s.row_cache_mb, "bound of the cache of shooters' rows, MiB")->default_val(s.row_cache_mb));
    expert(sub->add_option("--batch", opts->batch, "shooters whose rows are computed together (default: 16, as solve)"));
    auto& v = opts->viewer;
    sub->add_option("--size", opts->size, "window size WxH")->default_val(opts->size);
    expert(sub->add_option("--budget-ms", v.budget_ms, "solver time per frame, milliseconds (adjustable in the window)")
        ->default_val(v.budget_ms));
    expert(sub->add_option("--shots-per-frame", v.shots_per_frame, "at most this many shots per frame (0: as the budget allows)"));
    sub->add_option("--exposure", opts->exposure, "exposure in stops (default: from the scene's emitted power)");
    sub->add_option("--tone-map", v.tone_map, "clamp, reinhard or aces")
        ->check(CLI::IsMember({"clamp", "reinhard", "aces"}))
        ->default_val(v.tone_map);
    sub->add_flag("--no-ambient", opts->no_ambient, "do not add the ambient term to the display");
    sub->add_flag("--flat", v.flat, "flat patch shading (default: smooth, vertex-interpolated)");
    sub->add_flag("--wireframe", v.wireframe, "draw patch outlines");
    expert(sub->add_flag("--hide-ui", v.hide_ui, "start with the panel hidden (H toggles it)"));
    expert(sub->add_flag("--paused", v.paused, "start with the solver paused (Space resumes)"));
    expert(sub->add_option("--frames", v.frames, "run this many frames, then save --screenshot/--exr and exit"));
    expert(sub->add_option("--pick", opts->pick, "after the frames, inspect the patch at window pixel X,Y (from the top left)"));
    expert(sub->add_option("--screenshot", v.screenshot, "after the frames, save the window as PNG"));
    expert(sub->add_option("--exr", v.exr, "after the frames, save the linear radiosity of the view as OpenEXR"));
    expert(sub->add_flag("--until-done", v.until_done,
                  "run frames until the (last adaptive level's) solve stops, then act as after --frames"));
    sub->add_option("--objects", opts->objects, "at the end, write the radiosity per object as solve --objects does");
    sub->callback([opts, &action] {
        action = [opts] {
            if (opts->scene.quiet) set_log_level(LogLevel::Quiet);
            return run(*opts);
        };
    });
}

}  // namespace ffcube::cli
