// ffcube bench: hemicube and ray-cast form factors against analytic values, error against time.
#include <fmt/format.h>

#include <cmath>
#include <filesystem>

#include "cli/commands.hpp"
#include "ffcube/bench/bench.hpp"
#include "ffcube/core/error.hpp"
#include "ffcube/core/log.hpp"
#include "ffcube/io/report.hpp"
#include "ffcube/pipeline/scene_loading.hpp"

namespace ffcube::cli {
namespace {

struct Options {
    std::string suite = "all";
    std::vector<int> resolutions;
    std::vector<std::uint64_t> rays;
    std::vector<double> tolerances;
    bool quick = false;
    std::string out = "bench-results";
    unsigned threads = 0;
    std::string backend = "auto";
    std::uint64_t seed = 0x5eed;
    bool quiet = false;
    bool no_correct = false;
    std::string scene;
};

int run(const Options& o) {
    BenchOptions b;
    b.suite = o.suite;
    b.quick = o.quick;
    b.threads = o.threads;
    b.backend = parse_backend(o.backend);
    b.seed = o.seed;
    b.corrected = !o.no_correct;
    // Defaults: the full sweep, or two settings per method with --quick (about a minute on 2 cores).
    b.resolutions = !o.resolutions.empty() ? o.resolutions
                    : o.quick            ? std::vector<int>{32, 128}
                                         : std::vector<int>{32, 64, 128, 256, 512};
    b.rays = !o.rays.empty() ? o.rays
             : o.quick       ? std::vector<std::uint64_t>{256, 4096}
                             : std::vector<std::uint64_t>{100, 1000, 10000, 100000};
    // Accuracy by target: 1e-2 … 1e-4. Each decade costs about 10 times the one before (1e-5
    // took 41 to 286 s a case of the quick suite on 2 shared cores: docs/benchmarks.md); ask for
    // it, or 1e-6, with --tolerances.
    b.tolerances = !o.tolerances.empty() ? o.tolerances
                   : o.quick            ? std::vector<double>{1e-2, 1e-3}
                                        : std::vector<double>{1e-2, 1e-3, 1e-4};

    const auto line = [](std::size_t done, std::size_t total, const BenchResult& r) {
        info("[{}/{}] {:<18} {:<9} {:<11} {:>9.3f} s  max abs err {:.3e}  rel {:.3e}{}", done, total, r.case_name, r.method,
             r.setting, r.seconds, r.errors.max_abs_error, r.errors.max_rel_error,
             std::isnan(r.estimate) ? std::string() : fmt::format("  estimate {:.3e}", r.estimate));
    };
    // The output directory, made once the inputs are known good (a bad --scene leaves nothing).
    const std::filesystem::path dir(o.out);
    const auto make_dir = [&] {
        std::error_code ec;
        std::filesystem::create_directories(dir, ec);
        if (ec || !std::filesystem::is_directory(dir))
            throw IoError(fmt::format("--out {}: cannot create the directory: {}", o.out, ec ? ec.message() : "not a directory"));
    };
    std::vector<BenchResult> results;
    if (!o.scene.empty()) {
        // A scene of the user's: one patch a face (as View3D, and as --no-subdivide makes a city),
        // the tolerance sweep on sampled rows against the ray caster with many rays.
        SceneOptions so;
        so.path = o.scene;
        so.subdivide = false;
        Report report;
        const Scene scene = load_and_mesh(so, report);
        make_dir();
        SceneSweepOptions sw;
        sw.tolerances = b.tolerances;
        sw.threads = o.threads;
        sw.seed = o.seed;
        info("--scene {}: {} patches; {} sampled rows against the ray caster at {} rays each", o.scene, scene.size(),
             sweep_sample(static_cast<std::uint32_t>(scene.size()), sw.sample_rows).size(), sw.reference_rays);
        results = run_scene_sweep(scene, std::filesystem::path(o.scene).stem().string(), sw, line);
    } else {
        make_dir();
        results = run_bench(bench_cases(o.quick), b, line);
    }
    write_bench_csv(dir / "results.csv", results);
    write_bench_json(dir / "results.json", results, b);
    write_bench_plot_svg(dir / "error_vs_time.svg", results);
    write_bench_plot_png(dir / "error_vs_time.png", results);
    info("wrote {}/results.csv, results.json, error_vs_time.svg, error_vs_time.png", o.out);
    return 0;
}

}  // namespace

void add_bench_command(CLI::App& app, std::function<int()>& action) {
    auto opts = std::make_shared<Options>();
    CLI::App* sub = app.add_subcommand("bench", "benchmark hemicube and ray-cast form factors against analytic values");
    sub->add_option("--suite", opts->suite, "all, basic, enclosure, proximity, extreme or occlusion")->default_val("all");
    sub->add_option("--resolutions", opts->resolutions, "hemicube resolutions, e.g. 32,64,128,256,512")->delimiter(',');
    sub->add_option("--rays", opts->rays, "ray-cast rays per patch, e.g. 100,1000,10000,100000")->delimiter(',');
    sub->add_option("--tolerances", opts->tolerances,
                    "accuracy targets of the ray caster refined to each (--tolerance), default 1e-2,1e-3,1e-4")
        ->delimiter(',');
    sub->add_option("--scene", opts->scene,
                    "instead of the exact cases: the tolerance sweep (--tolerances) on this scene, one patch a face, its sampled "
                    "rows against the ray caster with many rays (docs/commands.md)");
    sub->add_flag("--quick", opts->quick, "fewer cases, coarser meshes, two settings per method (about a minute)");
    sub->add_option("--out", opts->out, "directory for results.csv, results.json, error_vs_time.svg/.png")
        ->default_val("bench-results");
    sub->add_option("--threads", opts->threads, "worker threads for both methods (default: every core)");
    sub->add_option("--backend", opts->backend, "OpenGL context: auto, egl or osmesa")
        ->check(CLI::IsMember({"auto", "egl", "osmesa"}))
        ->default_val("auto");
    sub->add_option("--seed", opts->seed, "seed of hemicube rotations and ray sampling")->default_val(0x5eed);
    sub->add_flag("--no-correct", opts->no_correct,
                  "skip the method hemicube+near (each hemicube run's rows through the default --correct near)");
    sub->add_flag("-q,--quiet", opts->quiet, "no per-run lines on stderr");
    sub->callback([opts, &action] {
        action = [opts] {
            if (opts->quiet) set_log_level(LogLevel::Quiet);
            return run(*opts);
        };
    });
}

}  // namespace ffcube::cli
