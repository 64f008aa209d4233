// ffcube formfactors: headless precomputation of the form-factor matrix.
#include <fmt/format.h>

#include "cli/commands.hpp"
#include "cli/common.hpp"
#include "cli/row_store.hpp"
#include "ffcube/core/error.hpp"
#include "ffcube/core/log.hpp"
#include "ffcube/core/progress.hpp"
#include "ffcube/core/timer.hpp"
#include "ffcube/formfactor/checks.hpp"
#include "ffcube/io/csv.hpp"
#include "ffcube/io/ffm.hpp"
#include "ffcube/io/mtx.hpp"
#include "ffcube/raycast/raycast_provider.hpp"

namespace ffcube::cli {
namespace {

struct Options {
    SceneOptions scene;
    FormFactorOptions ff;
    std::string output, groups, report;
    CheckpointOptions checkpoint;
    std::string method = "hemicube";  // or "raycast" (Embree, no GL)
    std::uint64_t rays = 4096;          // raycast: rays per patch
};

bool ends_with(const std::string& s, std::string_view suffix) {
    return s.size() >= suffix.size() && s.compare(s.size() - suffix.size(), suffix.size(), suffix) == 0;
}

// Records the hemicube provider's figures in the report.
void report_hemicube(Report& r, const HemicubeRowProvider& provider) {
    const HemicubeStats st = provider.stats();
    r.set("backend", provider.backend());
    r.set("renderer", provider.renderer());
    r.set("resolution", provider.resolution());
    r.set("threads", provider.threads());
    r.set("workers", provider.workers());
    r.set("hemicubes", st.hemicubes);
    // CPU-seconds summed over worker threads.
    r.set("time.prepare", st.prepare_seconds);
    r.set("time.drawing", st.draw_seconds);
    r.set("time.readback", st.readback_seconds);
    r.set("time.accumulation", st.accumulate_seconds);
    // Culling is per mesher piece (a face's quad or triangle, drawn whole), summed over hemicubes.
    r.set("left_out.pieces_considered", st.pieces_considered);
    r.set("left_out.pieces_behind_plane", st.pieces_behind);
    const char* names[5] = {"top", "pos_x", "neg_x", "pos_y", "neg_y"};
    for (std::size_t f = 0; f < 5; ++f) {
        r.set(fmt::format("left_out.pieces_culled_per_face.{}", names[f]), st.pieces_culled[f]);
        r.set(fmt::format("drawn.pieces_per_face.{}", names[f]), st.pieces_drawn[f]);
    }
    const double h = st.hemicubes ? static_cast<double>(st.hemicubes) : 1.0;
    r.set("coverage.mean_miss_fraction", st.miss_weight / h);
    r.set("coverage.mean_back_face_fraction", st.back_face_weight / h);
    r.set("self_hits", st.self_hits);
}

int run(const Options& o) {
    const bool ffm = ends_with(o.output, ".ffm"), mtx = ends_with(o.output, ".mtx");
    if (!o.output.empty() && !ffm && !mtx)
        throw InputError(fmt::format("--output {}: the name must end in .ffm (ffcube's format) or .mtx (Matrix Market)", o.output));
    check_output_path("--output", o.output);
    check_output_path("--groups", o.groups);
    check_output_path("--report", o.report);
    const bool raycast = o.method == "raycast";
    const HemicubeOptions hopt = hemicube_options(o.ff);
    if (raycast && o.rays == 0) throw InputError("--rays 0: at least 1 ray per patch");

    Report report;
    report.set("command", "formfactors");
    Scene scene = load_and_mesh(o.scene, report);
    FfmMetadata meta;
    if (raycast) {
        meta.method = "raycast";
        meta.settings = fmt::format("rays={} seed={}", o.rays, o.ff.seed);
    } else {
        meta.method = "hemicube";
        meta.resolution = static_cast<std::uint32_t>(hopt.resolution);
        meta.settings = fmt::format("rotate={} seed={}", hopt.rotate ? 1 : 0, hopt.seed);
    }
    std::optional<RowCheckpoint> checkpoint = open_checkpoint(o.checkpoint, scene, meta, report);

    Stopwatch total;
    Stopwatch watch;
    std::unique_ptr<HemicubeRowProvider> hemicube;
    std::unique_ptr<RaycastRowProvider> raycaster;
    if (raycast) {
        RaycastOptions ropt;
        ropt.rays = o.rays;
        ropt.threads = o.ff.threads;
        ropt.seed = o.ff.seed;
        raycaster = std::make_unique<RaycastRowProvider>(scene, ropt);
        report.set("time.setup", watch.seconds());
        info("raycast (Embree), {} thread(s), {} rays per patch", raycaster->threads(), raycaster->rays());
    } else {
        hemicube = std::make_unique<HemicubeRowProvider>(scene, hopt);
        report.set("time.context_setup", watch.seconds());
        info("{} on {} ({}), {} thread(s), resolution {}", hemicube->name(), hemicube->backend(), hemicube->renderer(),
             hemicube->threads(), hemicube->resolution());
    }
    RowProvider& provider = raycast ? static_cast<RowProvider&>(*raycaster) : *hemicube;
    report.set("method", provider.name());

    watch.restart();
    const CsrMatrix F = compute_matrix(provider, checkpoint ? &*checkpoint : nullptr, !o.scene.quiet);
    const double seconds = watch.seconds();
    report.set("seconds", seconds);
    report.set(raycast ? "rows_per_second" : "hemicubes_per_second", static_cast<double>(scene.size()) / std::max(seconds, 1e-9));
    report.set("nnz", F.nnz());
    report.set("skipped_rows", 0);
    if (raycast) {
        report.set("rays_per_patch", raycaster->rays());
        report.set("rays_traced", raycaster->rays_traced());
        report.set("threads", raycaster->threads());
    } else {
        report_hemicube(report, *hemicube);
    }

    const RowSumStats rs = row_sum_stats(F);
    const ReciprocityStats rec = reciprocity_stats(F, scene);
    report.set("row_sums.min", rs.min);
    report.set("row_sums.max", rs.max);
    report.set("row_sums.mean", rs.mean);
    report.set("reciprocity.patch_max_abs", rec.patch_max_abs);
    report.set("reciprocity.object_max_rel", rec.object_max_rel);
    info("{} rows in {:.2f} s ({:.0f} rows/s); row sums {:.6f}..{:.6f} (mean {:.6f}); reciprocity (objects) {:.2e}",
         scene.size(), seconds, static_cast<double>(scene.size()) / std::max(seconds, 1e-9), rs.min, rs.max, rs.mean,
         rec.object_max_rel);

    watch.restart();
    if (ffm) {
        write_ffm(o.output, F, scene, meta);
    } else if (mtx) {
        write_mtx(o.output, F);
    }
    if (!o.groups.empty()) write_groups_csv(o.groups, object_form_factors(F, scene), scene.objects);
    report.set("time.writing", watch.seconds());
    report.set("time.total", total.seconds());
    if (!o.report.empty()) report.write(o.report);
    return 0;
}

}  // namespace

void add_formfactors_command(CLI::App& app, std::function<int()>& action) {
    auto opts = std::make_shared<Options>();
    CLI::App* sub = app.add_subcommand("formfactors", "compute the form-factor matrix of a scene with hemicubes");
    add_scene_options(*sub, opts->scene);
    add_formfactor_options(*sub, opts->ff);
    sub->add_option("-o,--output", opts->output, "write F to F.ffm (ffcube's binary format) or F.mtx (Matrix Market)");
    sub->add_option("--groups", opts->groups, "write object-to-object form factors as CSV (from,to,F)");
    sub->add_option("--method", opts->method, "hemicube (OpenGL) or raycast (Monte Carlo through Embree, no GL)")
        ->check(CLI::IsMember({"hemicube", "raycast"}))
        ->default_val("hemicube");
    sub->add_option("--rays", opts->rays, "raycast: rays per patch (standard error of F about sqrt(F(1-F)/rays))")
        ->default_val(4096);
    sub->add_option("--report", opts->report, "write a JSON report (timings, row sums, reciprocity, culling)");
    add_checkpoint_options(*sub, opts->checkpoint);
    sub->callback([opts, &action] {
        action = [opts] {
            if (opts->scene.quiet) set_log_level(LogLevel::Quiet);
            return run(*opts);
        };
    });
}

}  // namespace ffcube::cli
