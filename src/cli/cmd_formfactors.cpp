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

namespace ffcube::cli {
namespace {

struct Options {
    SceneOptions scene;
    FormFactorOptions ff;
    std::string output, groups, report;
    CheckpointOptions checkpoint;
};

bool ends_with(const std::string& s, std::string_view suffix) {
    return s.size() >= suffix.size() && s.compare(s.size() - suffix.size(), suffix.size(), suffix) == 0;
}


int run(const Options& o) {
    const bool ffm = ends_with(o.output, ".ffm"), mtx = ends_with(o.output, ".mtx");
    if (!o.output.empty() && !ffm && !mtx)
        throw InputError(fmt::format("--output {}: the name must end in .ffm (ffcube's format) or .mtx (Matrix Market)", o.output));
    check_output_path("--output", o.output);
    check_output_path("--groups", o.groups);
    check_output_path("--report", o.report);
    hemicube_options(o.ff);  // validates before any work

    Report report;
    report.set("command", "formfactors");
    Scene scene = load_and_mesh(o.scene, report);
    const FfmMetadata meta = row_metadata(o.ff);
    std::optional<RowCheckpoint> checkpoint = open_checkpoint(o.checkpoint, scene, meta, report);

    Stopwatch total;
    RowSource rows = make_row_source(scene, o.ff, report);
    RowProvider& provider = rows.provider();

    Stopwatch watch;
    watch.restart();
    CsrMatrix computed = compute_matrix(provider, checkpoint ? &*checkpoint : nullptr, !o.scene.quiet);
    const double seconds = watch.seconds();
    const CsrMatrix F = apply_enforcement(o.ff, std::move(computed), scene, rows, report);
    report.set("seconds", seconds);
    report.set(rows.raycast ? "rows_per_second" : "hemicubes_per_second", static_cast<double>(scene.size()) / std::max(seconds, 1e-9));
    report.set("nnz", F.nnz());
    report_row_source(report, rows);

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
        // The written matrix records its enforcement too (the checkpoint's rows are from before
        // it, so `meta` without it is what resuming compares).
        FfmMetadata written = meta;
        if (!o.ff.enforce.empty()) written.settings += " enforce=" + o.ff.enforce;
        write_ffm(o.output, F, scene, written);
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
    CLI::App* sub = app.add_subcommand("formfactors", "compute the form-factor matrix of a scene (hemicubes, or rays with --method raycast)");
    add_scene_options(*sub, opts->scene);
    add_formfactor_options(*sub, opts->ff);
    add_enforce_option(*sub, opts->ff);
    sub->add_option("-o,--output", opts->output, "write F to F.ffm (ffcube's binary format) or F.mtx (Matrix Market)");
    sub->add_option("--groups", opts->groups, "write object-to-object form factors as CSV (from,to,F)");
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
