// ffcube formfactors: headless precomputation of the form-factor matrix.
#include <fmt/format.h>

#include <algorithm>
#include <cstdlib>
#include <memory>
#include <optional>
#include <vector>

#include "cli/commands.hpp"
#include "cli/common.hpp"
#include "cli/expert.hpp"
#include "cli/mpi_glue.hpp"
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
#include "ffcube/io/solver_files.hpp"
#include "ffcube/io/transpose_scratch.hpp"
#include "ffcube/pipeline/enforcement.hpp"
#include "ffcube/pipeline/row_source.hpp"
#include "ffcube/pipeline/scene_loading.hpp"
#include "ffcube/pipeline/surface_outputs.hpp"
#include "ffcube/scene/patch_areas.hpp"

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

struct Figures {
    double seconds = 0;  // computing the rows (streamed: with coding and writing them)
    std::uint64_t nnz = 0;
    RowSumStats row_sums;
    ReciprocityStats reciprocity;
    std::vector<std::vector<double>> groups;
};

// Hands every row, in row order, to a sink (as the floats CsrMatrix holds): stream_rows, or under
// mpirun the ranks' blocks (mpi_stream_rows), which returns the figures of every rank's rows
// (nullopt: the RowSource's own are every row's).
using RowSinkFn = std::function<void(std::uint32_t, RowView)>;
using RowFeed = std::function<std::optional<RanksFigures>(const RowSinkFn&)>;

// Per row, the share obstruction-only surfaces intercepted (for the sky outputs; empty without
// them): under mpirun the ranks' gathered on rank 0; with a checkpoint the shares stored with its
// rows (reused or computed: a resumed run's are the uninterrupted run's bits); else the
// RowSource's, which saw every row.
std::span<const double> obstructed_shares(const Scene& scene, const RowSource& rows, const RowCheckpoint* cp,
                                          const std::optional<RanksFigures>& ranks) {
    if (!scene.drawn) return {};
    if (ranks) return ranks->obstructed;
    if (cp) return cp->obstructed();
    return rows.obstructed();
}

// Each row's estimate as the tolerance holds it (largest entry, sum), for the patch table (none
// without the correction).
std::span<const float> row_errors(const RowSource& rows) {
    return rows.corrected() ? std::span<const float>(rows.corrected()->row_tolerance_estimates()) : std::span<const float>{};
}

// Rows straight to the outputs as they come (.ffm, .mtx, Elmer's file: MatrixSink), statistics
// from the stream and from passes over a written .ffm: memory independent of the number of entries
// (docs/robustness.md). The computed rows go to an .ffm: the output itself, or a scratch file when
// the output is a .mtx or with --enforce, whose enforced rows then go to the outputs
// (pipeline/enforcement.hpp).
Figures streamed(const Options& o, const Scene& scene, RowSource& rows, const RowFeed& feed,
                 const FfmMetadata& written, Report& report, const RowCheckpoint* cp) {
    const bool progress = !o.scene.quiet;
    const bool enforce = rows.options().enforce != EnforceRequest::None;
    const bool ffm = o.output.ends_with(".ffm");
    const std::uint64_t budget_bytes = o.stats_memory_mib << 20;
    const auto n = static_cast<std::uint32_t>(scene.size());
    Figures f;
    RowStreamChecks checks(scene);
    std::vector<double> sums(scene.size(), 0.0);  // for the sky view factors: 8 bytes a patch
    ScratchDir scratch(o.output);  // removed on return and on error
    std::optional<RanksFigures> ranks;
    // The finished rows' files besides the .ffm, each created now so that a bad path fails before
    // any row is computed.
    std::vector<std::unique_ptr<MatrixSink>> sinks;
    if (o.output.ends_with(".mtx")) sinks.push_back(std::make_unique<MtxWriter>(o.output, n, progress));
    if (auto elmer = open_elmer_sink(o.outputs, n)) sinks.push_back(std::move(elmer));
    const auto report_ffm = [&](const FfmWriter& w) {
        report.set("ffm.bytes", w.bytes_written());
        report.set("ffm.bytes_per_nnz", static_cast<double>(w.bytes_written()) / std::max(1.0, static_cast<double>(w.nnz())));
    };
    // Without --enforce the computed rows are the output .ffm when there is one; else a scratch
    // file (fast compression: it is read twice and removed).
    const bool first_is_output = ffm && !enforce;
    const std::filesystem::path first = first_is_output ? std::filesystem::path(o.output) : scratch.path() / "computed.ffm";
    const std::vector<double> areas = patch_areas(scene);
    // Reciprocity while the rows come, when the entries waiting for their column's row stay
    // within min(--stats-memory, 64 MiB) at 16 bytes each (scenes to about 10k patches): then
    // no pass over the file follows. Beyond, it gives up and frees them, and the file is read.
    constexpr std::uint64_t kLiveReciprocityBytes = std::uint64_t{64} << 20;
    std::optional<StreamedPatchReciprocity> live;
    if (!enforce) live.emplace(areas, std::min(budget_bytes, kLiveReciprocityBytes) / 16);
    {
        FfmWriter writer(first, scene, written, first_is_output ? FfmWriterOptions{} : FfmWriterOptions{1u << 20, 1});
        Stopwatch watch, piece;
        double writing = 0;  // coding, compressing and writing, between the rows
        ranks = feed([&](std::uint32_t i, RowView row) {
            piece.restart();
            writer.append_row(row);
            if (!enforce)
                for (const auto& sink : sinks) sink->append_row(row);
            writing += piece.seconds();
            checks.add(i, row);
            if (live) live->add(i, row);
            sums[i] = row.sum();
        });
        f.seconds = watch.seconds();
        piece.restart();
        // fsync of a large file can take many seconds (14 s for 5.3 GB at 100k patches, and no line).
        if (progress) info("closing {}: its last block, fsync and rename", first.filename().string());
        writer.finish();
        if (!enforce)
            for (const auto& sink : sinks) sink->finish();
        report.set("time.writing", writing + piece.seconds());
        f.nnz = writer.nnz();
        if (first_is_output) report_ffm(writer);
    }
    Stopwatch watch;
    const RowStreamChecks* final_checks = &checks;
    std::optional<RowStreamChecks> out_checks;
    if (enforce) {
        out_checks.emplace(scene);
        std::optional<FfmWriter> writer;
        if (ffm) writer.emplace(o.output, scene, written);
        std::uint64_t nnz = 0;
        const StreamedEnforcement e = apply_enforcement_streamed(
            rows, first, checks, sums, scene, scratch.path(), budget_bytes, progress,
            [&](std::uint32_t i, RowView row) {
                if (writer) writer->append_row(row);
                for (const auto& sink : sinks) sink->append_row(row);
                out_checks->add(i, row);
                sums[i] = row.sum();
                nnz += row.col.size();
            },
            report, ranks ? &ranks->evidence : nullptr);
        if (writer) {
            writer->finish();
            report_ffm(*writer);
        }
        for (const auto& sink : sinks) sink->finish();
        f.nnz = nnz;
        final_checks = &*out_checks;
        f.reciprocity.patch_max_abs = e.patch_max_abs;  // computed with the enforced rows
    } else if (live && live->complete()) {
        if (progress)
            info("reciprocity: checked while the rows came ({:.1f} MiB held at most), no pass over {}",
                 static_cast<double>(live->peak_entries()) * 8 / (1 << 20), first.filename().string());
        f.reciprocity.patch_max_abs = live->max_abs();
        report.set("reciprocity.passes", 0);
        report.set("reciprocity.bands", 0);
        report.set("reciprocity.scratch_bytes", 0);
        report.set("reciprocity.in_stream_peak_entries", live->peak_entries());
    } else {
        live.reset();
        // Each row with its column (F_ji), by bands of columns of at most --stats-memory (8 bytes
        // per entry held): a pass over the file spills the bands to scratch files, a second reads
        // the rows again with the bands one at a time (io/transpose_scratch.hpp); when the one band
        // and the rows fit together, one pass keeps both.
        // Only the columns' parts below the diagonal: the measure is symmetric in the pair, so each
        // pair is looked at once, from its lower row (half the entries to hold and spill).
        const TransposePlan plan =
            plan_transpose(checks.lower_col_counts(), std::max<std::uint64_t>(1, budget_bytes / 8), checks.upper_entries());
        FfmReader reader(first);
        PatchReciprocity patch(areas);
        Progress bar(fmt::format("reciprocity ({} pass{} over {}, {} band{})", plan.passes, plan.passes == 1 ? "" : "es",
                                 first.filename().string(), plan.band_count(), plan.band_count() == 1 ? "" : "s"),
                     std::uint64_t(scene.size()) * plan.passes, progress);
        const TransposeFigures t = for_each_row_and_column(
            [&](const std::function<void(std::uint32_t, RowView)>& g) { reader.for_each_row(g); },
            checks.lower_col_counts(), plan, scratch.path(),
            [&](std::uint32_t i, RowView row, RowView column) { patch.add(i, row, column); }, &bar,
            ColumnPart::below_diagonal);
        f.reciprocity.patch_max_abs = patch.max_abs();
        report.set("reciprocity.passes", t.passes);
        report.set("reciprocity.bands", plan.band_count());
        report.set("reciprocity.scratch_bytes", t.scratch_bytes);
    }
    f.row_sums = final_checks->row_sums();
    f.reciprocity.object_max_rel = final_checks->object_max_rel();
    if (!o.groups.empty()) f.groups = final_checks->object_factors();
    report.set("time.statistics", watch.seconds());
    write_surface_outputs(o.outputs, sums, *final_checks, scene, report, obstructed_shares(scene, rows, cp, ranks),
                          row_errors(rows));
    return f;
}

// The matrix in memory: no output (or the test hook FFCUBE_TEST_IN_MEMORY).
// `computed` holds every row (from this process, or gathered from the MPI ranks), computed in
// `seconds`; `ranks`: under mpirun, the figures of every rank's rows.
Figures in_memory(const Options& o, const Scene& scene, RowSource& rows, CsrMatrix computed, double seconds,
                  const FfmMetadata& written, Report& report, const std::optional<RanksFigures>& ranks,
                  const RowCheckpoint* cp) {
    const bool progress = !o.scene.quiet;
    Figures f;
    Stopwatch watch;
    f.seconds = seconds;
    const CsrMatrix F = apply_enforcement(rows, std::move(computed), scene, report, ranks ? &ranks->evidence : nullptr, progress);
    f.nnz = F.nnz();
    f.row_sums = row_sum_stats(F);
    {
        Progress bar("reciprocity", F.size(), progress);
        f.reciprocity = reciprocity_stats(F, scene, &bar);
    }
    watch.restart();
    if (o.output.ends_with(".ffm")) {
        Progress bar(fmt::format("writing {}", o.output), ffm_progress_total(F, kFfmVersion), progress);
        write_ffm(o.output, F, scene, written, &bar, kFfmVersion);
    } else if (o.output.ends_with(".mtx")) {
        Progress bar(fmt::format("writing {} (rows)", o.output), F.size(), progress);
        write_mtx(o.output, F, &bar);
    }
    if (!o.groups.empty()) f.groups = object_form_factors(F, scene);
    write_surface_outputs(o.outputs, F, scene, report, progress, obstructed_shares(scene, rows, cp, ranks),
                          row_errors(rows));
    report.set("time.writing", watch.seconds());
    return f;
}

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
    // Under mpirun rank 0 takes the ranks' rows in row order, a chunk at a time (mpi_stream_rows).
    // FFCUBE_TEST_IN_MEMORY (set, non-empty): a test hook that takes the in-memory path, so that
    // tests compare it with the streamed one byte for byte.
    const char* test_in_memory = std::getenv("FFCUBE_TEST_IN_MEMORY");
    const bool stream = (ffm || mtx) && !(test_in_memory && *test_in_memory);
    report.set("streamed", stream);
    Figures f;
    if (stream) {
        const bool progress = !o.scene.quiet;
        // Under mpirun rank 0 takes the ranks' blocks in row order, a chunk at a time (the same bytes).
        const RowFeed feed = [&](const RowSinkFn& sink) -> std::optional<RanksFigures> {
            if (distributed)
                return mpi_stream_rows(rows, scene, row_options, o.checkpoint, meta, o.output, report, progress, sink);
            stream_rows(rows.provider(), cp, progress, sink, rows.obstructed());
            return std::nullopt;
        };
        if (!mpi_root()) {  // this rank's block computed and sent to rank 0: its part is done
            feed({});
            return 0;
        }
        f = streamed(o, scene, rows, feed, written, report, cp);
    } else {
        Stopwatch watch;
        CsrMatrix computed;
        std::optional<RanksFigures> ranks;
        if (distributed) {  // every rank its block; rank 0 gathers them and goes on alone
            ranks.emplace();
            std::optional<CsrMatrix> all =
                mpi_compute_matrix(rows, scene, row_options, o.checkpoint, meta, report, !o.scene.quiet, &*ranks);
            if (!all) return 0;
            computed = std::move(*all);
        } else {
            computed = compute_matrix(rows.provider(), cp, !o.scene.quiet, rows.obstructed());
        }
        f = in_memory(o, scene, rows, std::move(computed), watch.seconds(), written, report, ranks, cp);
    }
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
    if (!o.groups.empty()) write_groups_csv(o.groups, f.groups, scene.objects);
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
