// ffcube formfactors: headless precomputation of the form-factor matrix.
#include <fmt/format.h>

#include <algorithm>
#include <memory>
#include <optional>

#include "cli/commands.hpp"
#include "cli/common.hpp"
#include "cli/expert.hpp"
#include "cli/mpi_glue.hpp"
#include "cli/surface_options.hpp"
#include "ffcube/core/error.hpp"
#include "ffcube/core/log.hpp"
#include "ffcube/core/timer.hpp"
#include "ffcube/io/csv.hpp"
#include "ffcube/pipeline/enforcement.hpp"
#include "ffcube/pipeline/form_factors.hpp"
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
    std::uint64_t stats_memory_mib = 512;
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
    Scene scene = mpi_load_and_mesh(o.scene.scene, report);  // under mpirun: rank 0's, broadcast
    // --method auto, resolved here so that the fingerprint, the MPI ranks' blocks and the rows
    // all see the method the scene gets.
    RowOptions row_options = resolve_row_method(mpi_row_options(o.rows), scene.drawn_scene());
    apply_view3d_controls(scene, row_options, report);  // a .vs3's encl=1: --enforce closure
    refuse_enforcement_with_obstructions(row_options.enforce, scene);  // before any row
    const FfmMetadata meta = row_metadata(row_options);
    const bool distributed = mpi_distributed();  // under mpirun: a shard per rank instead
    std::optional<RowCheckpoint> checkpoint =
        distributed ? std::nullopt : open_checkpoint(o.checkpoint, scene, meta, report);

    Stopwatch total;
    RowSource rows = make_row_source(scene, row_options);
    for (const std::string& line : describe(rows)) info("{}", line);

    // The written matrix records its enforcement too (the checkpoint's rows are from before it,
    // so `meta` without it is what resuming compares).
    FfmMetadata written = meta;
    if (row_options.enforce != EnforceRequest::None)
        written.settings += fmt::format(" enforce={}", to_string(row_options.enforce));
    RowCheckpoint* cp = checkpoint ? &*checkpoint : nullptr;
    const bool progress = !o.scene.quiet;
    // Under mpirun rank 0 takes the ranks' rows in row order, a chunk at a time; the other ranks
    // compute their blocks and send them (their part is then done).
    std::unique_ptr<RowFeed> feed;
    if (distributed)
        feed = mpi_row_feed(rows, scene, row_options, o.checkpoint, meta, o.output, report, progress);
    else
        feed = std::make_unique<LocalRowFeed>(rows, cp, progress);
    if (!mpi_root()) {
        feed->rows({});
        return 0;
    }
    report.set("streamed", true);  // every run: the one path (pipeline/form_factors.hpp); a key reports read
    FormFactorOptions fo;
    fo.output = o.output;
    fo.written = written;
    fo.surface = o.outputs;
    fo.stats_memory_bytes = o.stats_memory_mib << 20;
    fo.object_factors = !o.groups.empty();
    fo.progress = progress;
    const FormFactorFigures f = compute_form_factors(scene, rows, *feed, fo, {}, report);
    const double seconds = f.seconds;
    report.set("seconds", seconds);
    report_rates(report, rows, scene.size(), seconds);
    report_row_source(report, rows);
    const RowSumStats& rs = f.row_sums;
    const ReciprocityStats& rec = f.reciprocity;
    report_matrix_stats(report, f.nnz, rs, rec);
    info("{} rows in {:.2f} s ({:.0f} rows/s); row sums {:.6f}..{:.6f} (mean {:.6f}); reciprocity (objects) {:.2e}",
         scene.size(), seconds, static_cast<double>(scene.size()) / std::max(seconds, 1e-9), rs.min, rs.max, rs.mean,
         rec.object_max_rel);
    if (!o.groups.empty()) write_groups_csv(o.groups, f.object_factors, scene.objects);
    report.set("time.total", total.seconds());
    if (!o.report.empty()) report.write(o.report);
    return 0;
}

}  // namespace

void add_formfactors_command(CLI::App& app, std::function<int()>& action) {
    auto opts = std::make_shared<Options>();
    CLI::App* sub = app.add_subcommand("formfactors", "compute the form-factor matrix of a scene (hemicubes or rays: --method)");
    add_scene_options(*sub, opts->scene);
    add_row_options(*sub, opts->rows);
    add_enforce_option(*sub, opts->rows);
    sub->add_option("-o,--output", opts->output, "write F to F.ffm (ffcube's binary format) or F.mtx (Matrix Market)");
    sub->add_option("--groups", opts->groups, "write object-to-object form factors as CSV (from,to,F)");
    sub->add_option("--report", opts->report, "write a JSON report (timings, row sums, reciprocity, culling)");
    add_checkpoint_options(*sub, opts->checkpoint);
    add_surface_output_options(*sub, opts->outputs);
    expert(sub->get_option("--materials"));  // Kd and Ke: nothing a form factor depends on
    expert(sub->add_option("--stats-memory", opts->stats_memory_mib,
                    "MiB for the reciprocity check and --enforce of a streamed .ffm (a band of the transpose, and G: less makes more scratch files)")
        ->check(CLI::Range(std::uint64_t{1}, std::uint64_t{1} << 30)));
    sub->callback([opts, &action] {
        action = [opts] {
            if (opts->scene.quiet) set_log_level(LogLevel::Quiet);
            return run(*opts);
        };
    });
}

}  // namespace ffcube::cli
