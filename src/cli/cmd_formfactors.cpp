// ffcube formfactors: headless precomputation of the form-factor matrix.
#include <fmt/format.h>

#include "cli/commands.hpp"
#include "cli/common.hpp"
#include "cli/row_store.hpp"
#include "cli/surface_options.hpp"
#include "ffcube/core/error.hpp"
#include "ffcube/core/log.hpp"
#include "ffcube/core/progress.hpp"
#include "ffcube/core/timer.hpp"
#include "ffcube/formfactor/checks.hpp"
#include "ffcube/io/csv.hpp"
#include "ffcube/io/ffm.hpp"
#include "ffcube/io/mtx.hpp"
#include "ffcube/pipeline/row_source.hpp"
#include "ffcube/pipeline/scene_loading.hpp"
#include "ffcube/pipeline/surface_outputs.hpp"

namespace ffcube::cli {
namespace {

struct Options {
    SceneFlags scene;
    RowOptions rows;
    std::string output, groups, report;
    CheckpointOptions checkpoint;
    SurfaceOutputOptions outputs;  // --sky, --view3d, --elmer, --patch-table
};

int run(const Options& o) {
    const bool ffm = o.output.ends_with(".ffm"), mtx = o.output.ends_with(".mtx");
    if (!o.output.empty() && !ffm && !mtx)
        throw InputError(fmt::format("--output {}: the name must end in .ffm (ffcube's format) or .mtx (Matrix Market)", o.output));
    check_output_path("--output", o.output);
    check_output_path("--groups", o.groups);
    check_output_path("--report", o.report);
    check_surface_output_paths(o.outputs);
    validate(o.rows);  // before any work

    Report report;
    report.set("command", "formfactors");
    Scene scene = load_and_mesh(o.scene.scene, report);
    RowOptions row_options = o.rows;
    apply_view3d_controls(scene, row_options, report);  // a .vs3's encl=1: --enforce closure
    const FfmMetadata meta = row_metadata(row_options);
    std::optional<RowCheckpoint> checkpoint = open_checkpoint(o.checkpoint, scene, meta, report);

    Stopwatch total;
    RowSource rows = make_row_source(scene, row_options);
    for (const std::string& line : describe(rows)) info("{}", line);
    RowProvider& provider = rows.provider();

    Stopwatch watch;
    watch.restart();
    CsrMatrix computed = compute_matrix(provider, checkpoint ? &*checkpoint : nullptr, !o.scene.quiet);
    const double seconds = watch.seconds();
    const CsrMatrix F = apply_enforcement(rows, std::move(computed), scene, report);
    report.set("seconds", seconds);
    report.set(rows.raycast() ? "rows_per_second" : "hemicubes_per_second",
               static_cast<double>(scene.size()) / std::max(seconds, 1e-9));
    report.set("nnz", F.nnz());
    report_row_source(report, rows);

    const RowSumStats rs = row_sum_stats(F);
    ReciprocityStats rec;
    {
        Progress progress("reciprocity", F.size(), !o.scene.quiet);
        rec = reciprocity_stats(F, scene, &progress);
    }
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
        // The written matrix records its enforcement too (the checkpoint's rows are from before
        // it, so `meta` without it is what resuming compares).
        FfmMetadata written = meta;
        if (row_options.enforce != EnforceRequest::None)
            written.settings += fmt::format(" enforce={}", to_string(row_options.enforce));
        Progress progress(fmt::format("writing {} (bytes)", o.output), ffm_payload_bytes(F), !o.scene.quiet);
        write_ffm(o.output, F, scene, written, &progress);
    } else if (mtx) {
        Progress progress(fmt::format("writing {} (rows)", o.output), F.size(), !o.scene.quiet);
        write_mtx(o.output, F, &progress);
    }
    if (!o.groups.empty()) write_groups_csv(o.groups, object_form_factors(F, scene), scene.objects);
    write_surface_outputs(o.outputs, F, scene, report, !o.scene.quiet);
    report.set("time.writing", watch.seconds());
    report.set("time.total", total.seconds());
    if (!o.report.empty()) report.write(o.report);
    return 0;
}

}  // namespace

void add_formfactors_command(CLI::App& app, std::function<int()>& action) {
    auto opts = std::make_shared<Options>();
    CLI::App* sub = app.add_subcommand("formfactors", "compute the form-factor matrix of a scene (hemicubes, or rays with --method raycast)");
    add_scene_options(*sub, opts->scene);
    add_row_options(*sub, opts->rows);
    add_enforce_option(*sub, opts->rows);
    sub->add_option("-o,--output", opts->output, "write F to F.ffm (ffcube's binary format) or F.mtx (Matrix Market)");
    sub->add_option("--groups", opts->groups, "write object-to-object form factors as CSV (from,to,F)");
    sub->add_option("--report", opts->report, "write a JSON report (timings, row sums, reciprocity, culling)");
    add_checkpoint_options(*sub, opts->checkpoint);
    add_surface_output_options(*sub, opts->outputs);
    sub->callback([opts, &action] {
        action = [opts] {
            if (opts->scene.quiet) set_log_level(LogLevel::Quiet);
            return run(*opts);
        };
    });
}

}  // namespace ffcube::cli
