#include "cli/row_store.hpp"

#include <fmt/format.h>

#include "ffcube/core/error.hpp"
#include "ffcube/core/log.hpp"
#include "ffcube/core/progress.hpp"

namespace ffcube::cli {

void add_checkpoint_options(CLI::App& app, CheckpointOptions& o) {
    auto* dir = app.add_option("--checkpoint", o.dir,
                               "stream finished rows to directory DIR (created if missing) so that a killed run can "
                               "be resumed");
    app.add_flag("--resume", o.resume,
                 "continue the checkpoint in --checkpoint DIR: reuse its rows (it must have been made by the same "
                 "scene and settings), compute the rest")
        ->needs(dir);
}

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

namespace {

// The rows missing from the checkpoint, each appended to its log as it comes.
void compute_into(RowProvider& provider, RowCheckpoint& checkpoint, bool progress, std::span<const double> obstructed) {
    const std::vector<std::uint32_t> rows = checkpoint.missing();
    {
        Progress bar("rows", rows.size(), progress);
        provider.compute_rows(rows, [&](std::uint32_t i, const SparseRow& row) {
            checkpoint.append(i, row, obstructed.empty() ? 0.0 : obstructed[i]);
            bar.add();
        });
    }
    checkpoint.sync();
}

}  // namespace

CsrMatrix compute_matrix(RowProvider& provider, RowCheckpoint* checkpoint, bool progress,
                         std::span<const double> obstructed) {
    const std::uint32_t n = provider.size();
    if (!checkpoint) {
        CsrMatrix F(n);
        Progress bar("rows", n, progress);
        std::vector<std::uint32_t> all(n);
        for (std::uint32_t i = 0; i < n; ++i) all[i] = i;
        provider.compute_rows(all, [&](std::uint32_t, const SparseRow& row) {
            F.append_row(row);
            bar.add();
        });
        return F;
    }
    compute_into(provider, *checkpoint, progress, obstructed);
    return checkpoint->assemble();
}

void stream_rows(RowProvider& provider, RowCheckpoint* checkpoint, bool progress,
                 const std::function<void(std::uint32_t, RowView)>& sink, std::span<const double> obstructed) {
    const std::uint32_t n = provider.size();
    if (!checkpoint) {
        Progress bar("rows", n, progress);
        std::vector<std::uint32_t> all(n);
        for (std::uint32_t i = 0; i < n; ++i) all[i] = i;
        std::vector<float> val;
        provider.compute_rows(all, [&](std::uint32_t i, const SparseRow& row) {
            val.resize(row.val.size());
            for (std::size_t k = 0; k < val.size(); ++k) val[k] = static_cast<float>(row.val[k]);  // as CsrMatrix
            sink(i, RowView{row.col, val});
            bar.add();
        });
        return;
    }
    compute_into(provider, *checkpoint, progress, obstructed);
    Progress bar("rows from the checkpoint", n, progress);
    checkpoint->for_each_row([&](std::uint32_t i, RowView row) {
        sink(i, row);
        bar.add();
    });
}

}  // namespace ffcube::cli
