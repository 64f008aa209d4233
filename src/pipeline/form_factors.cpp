// The one path of a finished matrix (pipeline/form_factors.hpp): rows from a feed into the sinks,
// --enforce, the statistics and the surface outputs.
#include "ffcube/pipeline/form_factors.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <memory>
#include <optional>
#include <vector>

#include "ffcube/core/error.hpp"
#include "ffcube/core/log.hpp"
#include "ffcube/core/progress.hpp"
#include "ffcube/core/timer.hpp"
#include "ffcube/io/mtx.hpp"
#include "ffcube/io/transpose_scratch.hpp"
#include "ffcube/pipeline/enforcement.hpp"
#include "ffcube/scene/patch_areas.hpp"

namespace ffcube {

CheckpointManifest checkpoint_manifest(const Scene& scene, const FfmMetadata& meta) {
    CheckpointManifest m;
    m.fingerprint = scene.fingerprint;
    m.patches = static_cast<std::uint32_t>(scene.size());
    m.meshing = scene.stats.how;
    m.max_patch_edge = scene.stats.max_patch_edge;
    m.meta = meta;
    // Each row's obstructed share goes with it: a resumed row needs it for the sky.
    m.obstructions = scene.drawn != nullptr;
    return m;
}

std::optional<RowCheckpoint> open_checkpoint(const CheckpointOptions& o, const Scene& scene, const FfmMetadata& meta,
                                             Report& report) {
    if (o.dir.empty()) return std::nullopt;
    const CheckpointManifest m = checkpoint_manifest(scene, meta);
    RowCheckpoint c = o.resume ? RowCheckpoint::resume(o.dir, m) : RowCheckpoint::create(o.dir, m);
    for (const std::string& w : c.warnings()) log_warning(w);
    if (o.resume) info("checkpoint {}: {} of {} rows already done", o.dir, c.rows_stored(), c.size());
    report.set("checkpoint.dir", o.dir);
    report.set("checkpoint.rows_reused", c.rows_stored());
    report.set("checkpoint.warnings", c.warnings().size());
    return c;
}

void LocalRowFeed::rows(const RowViewFn& sink) {
    RowProvider& provider = rows_.provider();
    const std::uint32_t n = provider.size();
    if (!checkpoint_) {
        Progress bar("rows", n, progress_);
        std::vector<std::uint32_t> all(n);
        for (std::uint32_t i = 0; i < n; ++i) all[i] = i;
        std::vector<float> val;
        provider.compute_rows(all, [&](std::uint32_t i, const SparseRow& row) {
            val.resize(row.val.size());
            for (std::size_t k = 0; k < val.size(); ++k) val[k] = static_cast<float>(row.val[k]);  // as CsrMatrix
            sink(i, RowView{row.col, val, row.side});
            bar.add();
        });
        return;
    }
    // The rows missing from the checkpoint, each appended to its log as it comes, then every row
    // read back from it: a resumed run's rows are the uninterrupted run's bits.
    const std::vector<std::uint32_t> missing = checkpoint_->missing();
    {
        Progress bar("rows", missing.size(), progress_);
        provider.compute_rows(missing, [&](std::uint32_t i, const SparseRow& row) {
            checkpoint_->append(i, row);  // with its side figures
            bar.add();
        });
    }
    checkpoint_->sync();
    Progress bar("rows from the checkpoint", n, progress_);
    checkpoint_->for_each_row([&](std::uint32_t i, RowView row) {
        sink(i, row);
        bar.add();
    });
}

ClosureEvidence LocalRowFeed::evidence() const { return closure_evidence(rows_); }

namespace {

// The rows as computed, kept for the passes after the last row (the reciprocity check when it was
// not done while the rows came, --enforce): a .ffm (the output itself, or a scratch file), or,
// when no file is written, a CsrMatrix in memory: the caller's own CsrMatrixSink when it is fed
// these very rows (no --enforce), else one of its own.
struct ComputedRows {
    std::optional<FfmWriter> file;
    std::filesystem::path path;
    std::optional<CsrMatrixSink> own;
    const CsrMatrixSink* memory = nullptr;
    // The sink to feed (null: the caller's, which the caller's sinks feed).
    MatrixSink* sink() { return file ? static_cast<MatrixSink*>(&*file) : own ? &*own : nullptr; }
    RowPass pass() const {
        if (memory) return [this](const RowViewFn& f) {
            const CsrMatrix& F = memory->matrix();
            for (std::uint32_t i = 0; i < F.size(); ++i) f(i, F.row(i));
        };
        return [this](const RowViewFn& f) { FfmReader(path).for_each_row(f); };
    }
    std::string name() const { return memory ? std::string("the rows in memory") : path.filename().string(); }
};

}  // namespace

FormFactorFigures compute_form_factors(const Scene& scene, RowSource& rows, RowFeed& feed,
                                       const FormFactorOptions& o, std::span<MatrixSink* const> caller_sinks,
                                       Report& report) {
    const bool progress = o.progress;
    const bool enforce = rows.options().enforce != EnforceRequest::None;
    const std::string output = o.output.string();
    const bool ffm = output.ends_with(".ffm"), mtx = output.ends_with(".mtx");
    FFCUBE_CHECK_MSG(output.empty() || ffm || mtx, "compute_form_factors: the output must be a .ffm or a .mtx");
    const std::uint64_t budget_bytes = o.stats_memory_bytes;
    const auto n = static_cast<std::uint32_t>(scene.size());
    FormFactorFigures f;
    RowStreamChecks checks(scene);
    std::vector<double> sums(scene.size(), 0.0);  // for the sky view factors: 8 bytes a patch
    // Made when first needed, removed on return and on error: next to the output, else in the
    // temporary directory.
    std::optional<ScratchDir> scratch;
    const auto scratch_dir = [&]() -> const std::filesystem::path& {
        if (!scratch) scratch.emplace(output.empty() ? std::filesystem::temp_directory_path() / "ffcube" : o.output);
        return scratch->path();
    };
    // The finished rows' files besides the .ffm, each created now so that a bad path fails before
    // any row is computed; then the caller's.
    std::vector<std::unique_ptr<MatrixSink>> files;
    if (mtx) files.push_back(std::make_unique<MtxWriter>(o.output, n, progress));
    if (auto elmer = open_elmer_sink(o.surface, n)) files.push_back(std::move(elmer));
    std::vector<MatrixSink*> sinks;
    for (const auto& s : files) sinks.push_back(s.get());
    sinks.insert(sinks.end(), caller_sinks.begin(), caller_sinks.end());
    const auto report_ffm = [&](const FfmWriter& w) {
        report.set("ffm.bytes", w.bytes_written());
        report.set("ffm.bytes_per_nnz",
                   static_cast<double>(w.bytes_written()) / std::max(1.0, static_cast<double>(w.nnz())));
    };
    // Without --enforce the computed rows are the output .ffm when there is one; else a scratch
    // file (fast compression: it is read twice and removed), or memory when no file is written.
    const bool first_is_output = ffm && !enforce;
    ComputedRows computed;
    if (first_is_output) {
        computed.path = o.output;
        computed.file.emplace(computed.path, scene, o.written);
    } else if (!output.empty()) {
        computed.path = scratch_dir() / "computed.ffm";
        computed.file.emplace(computed.path, scene, o.written, FfmWriterOptions{1u << 20, 1});
    } else {
        if (!enforce)
            for (MatrixSink* sink : caller_sinks)
                if (const auto* held = dynamic_cast<const CsrMatrixSink*>(sink)) computed.memory = held;
        if (!computed.memory) computed.memory = &computed.own.emplace(n);
    }
    const std::vector<double> areas = patch_areas(scene);
    // Reciprocity while the rows come into a file, when the entries waiting for their column's row
    // stay within min(--stats-memory, 64 MiB) at 16 bytes each (scenes to about 10k patches): then
    // no pass over the file follows. Beyond, it gives up and frees them, and the file is read
    // again. Rows held in memory are checked in place after the last (cheaper than waiting entries).
    constexpr std::uint64_t kLiveReciprocityBytes = std::uint64_t{64} << 20;
    std::optional<StreamedPatchReciprocity> live;
    if (!enforce && o.reciprocity && !computed.memory)
        live.emplace(areas, std::min(budget_bytes, kLiveReciprocityBytes) / 16);
    View3dCutoff cutoff(scene, o.max_distance);
    // Every row's side figures as it came (this process's, another rank's, a checkpoint's: a
    // resumed run's are the uninterrupted run's bits): the report's per-row figures, the sky's
    // obstructed shares, the patch table's estimates.
    RowLedger& ledger = rows.ledger();
    FFCUBE_CHECK(ledger.size() == n);
    {
        Stopwatch watch, piece;
        double writing = 0;  // coding, compressing and writing, between the rows
        std::uint64_t nnz = 0;
        feed.rows([&](std::uint32_t i, RowView as_computed) {
            ledger.note(i, as_computed.side);
            const RowView row = cutoff(i, as_computed);
            piece.restart();
            if (MatrixSink* keep = computed.sink()) keep->append_row(row);
            if (!enforce)
                for (MatrixSink* sink : sinks) sink->append_row(row);
            writing += piece.seconds();
            checks.add(i, row);
            if (live) live->add(i, row);
            sums[i] = row.sum();
            nnz += row.col.size();
        });
        f.seconds = watch.seconds();
        piece.restart();
        // fsync of a large file can take many seconds (14 s for 5.3 GB at 100k patches, and no line).
        if (progress && computed.file) info("closing {}: its last block, fsync and rename", computed.path.filename().string());
        if (MatrixSink* keep = computed.sink()) keep->finish();
        if (!enforce)
            for (MatrixSink* sink : sinks) sink->finish();
        report.set("time.writing", writing + piece.seconds());
        f.nnz = nnz;
        if (first_is_output) report_ffm(*computed.file);
    }
    Stopwatch watch;
    const RowStreamChecks* final_checks = &checks;
    std::optional<RowStreamChecks> out_checks;
    if (enforce) {
        out_checks.emplace(scene);
        std::optional<FfmWriter> writer;
        if (ffm) writer.emplace(o.output, scene, o.written);
        std::uint64_t nnz = 0;
        const EnforcementFigures e = apply_enforcement(
            rows.options(), computed.pass(), checks, sums, scene, feed.evidence(), scratch_dir(), budget_bytes,
            progress,
            [&](std::uint32_t i, RowView row) {
                if (writer) writer->append_row(row);
                for (MatrixSink* sink : sinks) sink->append_row(row);
                out_checks->add(i, row);
                sums[i] = row.sum();
                nnz += row.col.size();
            },
            report);
        if (writer) {
            writer->finish();
            report_ffm(*writer);
        }
        for (MatrixSink* sink : sinks) sink->finish();
        f.nnz = nnz;
        final_checks = &*out_checks;
        f.reciprocity.patch_max_abs = e.patch_max_abs;  // computed with the enforced rows
    } else if (!o.reciprocity) {
        // Not asked for: no pass.
    } else if (live && live->complete()) {
        if (progress)
            info("reciprocity: checked while the rows came ({:.1f} MiB held at most), no pass over {}",
                 static_cast<double>(live->peak_entries()) * 8 / (1 << 20), computed.name());
        f.reciprocity.patch_max_abs = live->max_abs();
        report.set("reciprocity.passes", 0);
        report.set("reciprocity.bands", 0);
        report.set("reciprocity.scratch_bytes", 0);
        report.set("reciprocity.in_stream_peak_entries", live->peak_entries());
    } else if (computed.memory) {
        // The rows are in memory: each entry's F_ji looked up in its row (reciprocity_stats: a
        // cursor per row, O(nnz), no transpose).
        Progress bar("reciprocity", n, progress);
        f.reciprocity.patch_max_abs = reciprocity_stats(computed.memory->matrix(), scene, &bar).patch_max_abs;
        report.set("reciprocity.passes", 1);
        report.set("reciprocity.bands", 0);
        report.set("reciprocity.scratch_bytes", 0);
    } else {
        live.reset();
        // Each row with its column (F_ji), by bands of columns of at most --stats-memory (8 bytes
        // per entry held): a pass over the rows spills the bands to scratch files, a second reads
        // the rows again with the bands one at a time (io/transpose_scratch.hpp); when the one band
        // and the rows fit together, one pass keeps both.
        // Only the columns' parts below the diagonal: the measure is symmetric in the pair, so each
        // pair is looked at once, from its lower row (half the entries to hold and spill).
        const TransposePlan plan = plan_transpose(checks.lower_col_counts(), std::max<std::uint64_t>(1, budget_bytes / 8),
                                                  checks.upper_entries());
        PatchReciprocity patch(areas);
        Progress bar(fmt::format("reciprocity ({} pass{} over {}, {} band{})", plan.passes, plan.passes == 1 ? "" : "es",
                                 computed.name(), plan.band_count(), plan.band_count() == 1 ? "" : "s"),
                     std::uint64_t(scene.size()) * plan.passes, progress);
        const TransposeFigures t = for_each_row_and_column(
            computed.pass(), checks.lower_col_counts(), plan, scratch_dir(),
            [&](std::uint32_t i, RowView row, RowView column) { patch.add(i, row, column); }, &bar,
            ColumnPart::below_diagonal);
        f.reciprocity.patch_max_abs = patch.max_abs();
        report.set("reciprocity.passes", t.passes);
        report.set("reciprocity.bands", plan.band_count());
        report.set("reciprocity.scratch_bytes", t.scratch_bytes);
    }
    f.row_sums = final_checks->row_sums();
    f.reciprocity.object_max_rel = final_checks->object_max_rel();
    if (o.object_factors) f.object_factors = final_checks->object_factors();
    report.set("time.statistics", watch.seconds());
    // The patch table's estimates: each row's as the tolerance holds it (largest entry, sum); none
    // without the correction.
    write_surface_outputs(o.surface, sums, *final_checks, scene, report,
                          scene.drawn ? ledger.obstructed() : std::span<const double>{},
                          rows.corrected() ? ledger.tolerance_errors() : std::span<const float>{});
    return f;
}

CsrMatrix form_factor_matrix(const Scene& scene, RowSource& rows, Report& report, const FormFactorOptions& options,
                             FormFactorFigures* figures) {
    FFCUBE_CHECK(options.output.empty());
    LocalRowFeed feed(rows, nullptr, options.progress);
    CsrMatrixSink matrix(static_cast<std::uint32_t>(scene.size()));
    MatrixSink* sinks[] = {&matrix};
    FormFactorFigures f = compute_form_factors(scene, rows, feed, options, sinks, report);
    if (figures) *figures = std::move(f);
    return matrix.take();
}

}  // namespace ffcube
