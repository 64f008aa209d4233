// The one path of a finished matrix: every row of F, in row order, from a RowFeed (this process's
// RowSource, through a checkpoint when one is asked for; or under mpirun the ranks' blocks) into
// the sinks (the .ffm or .mtx output, Elmer's file, a CsrMatrix in memory: io/matrix_sink.hpp),
// with --enforce, the statistics every front end reports (row sums, reciprocity, object factors)
// and the surface outputs (--sky, --view3d, --patch-table: pipeline/surface_outputs.hpp).
// `ffcube formfactors`, `ffcube view3d` and Python's form_factors all call compute_form_factors.
//
// Memory: with a file output, independent of the number of entries (the rows as computed go to
// the .ffm itself, or to a scratch .ffm for --enforce and a .mtx, which passes read again;
// docs/robustness.md, "Memory"). Without one, the rows as computed are held in memory (as a
// CsrMatrix) for those passes.
#pragma once

#include <cstdint>
#include <filesystem>
#include <functional>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "ffcube/accuracy/enforce.hpp"
#include "ffcube/formfactor/checks.hpp"
#include "ffcube/io/checkpoint.hpp"
#include "ffcube/io/ffm.hpp"
#include "ffcube/io/matrix_sink.hpp"
#include "ffcube/io/report.hpp"
#include "ffcube/pipeline/row_source.hpp"
#include "ffcube/pipeline/surface_outputs.hpp"
#include "ffcube/scene/scene.hpp"

namespace ffcube {

// --checkpoint DIR [--resume] (docs/robustness.md).
struct CheckpointOptions {
    std::string dir;  // empty: no checkpoint
    bool resume = false;
};

// What a checkpoint of this scene's rows made with these settings records (and resuming compares).
CheckpointManifest checkpoint_manifest(const Scene& scene, const FfmMetadata& meta);

// Opens the checkpoint (create, or resume: validated against this scene and these settings)
// before any expensive setup, so that a mismatch is refused at once. nullopt without a directory.
// Warnings about a damaged log are logged; rows reused are recorded in the report.
std::optional<RowCheckpoint> open_checkpoint(const CheckpointOptions& o, const Scene& scene, const FfmMetadata& meta,
                                             Report& report);

// Every row of F, in row order, as the floats CsrMatrix holds.
using RowViewFn = std::function<void(std::uint32_t, RowView)>;
class RowFeed {
public:
    virtual ~RowFeed() = default;
    // Hands every row 0..n-1 to sink, in order, each with its side figures (RowView::side).
    virtual void rows(const RowViewFn& sink) = 0;
    // After rows(): what the providers saw of whether the scene is closed, for all rows.
    virtual ClosureEvidence evidence() const = 0;
};

// This process's rows: straight from the RowSource, or with a checkpoint the rows missing from it
// computed into its log (each as it comes) and then every row read back from the log: the same
// bits as an uninterrupted run's. Progress bars when `progress`.
class LocalRowFeed final : public RowFeed {
public:
    LocalRowFeed(RowSource& rows, RowCheckpoint* checkpoint, bool progress)
        : rows_(rows), checkpoint_(checkpoint), progress_(progress) {}
    void rows(const RowViewFn& sink) override;
    ClosureEvidence evidence() const override;

private:
    RowSource& rows_;
    RowCheckpoint* checkpoint_;
    bool progress_;
};

struct FormFactorOptions {
    // F.ffm (version 2) or F.mtx, written from the rows as they come; empty: no file.
    std::filesystem::path output;
    FfmMetadata written;  // the .ffm's metadata (row_metadata, and " enforce=MODE" with --enforce)
    SurfaceOutputOptions surface;  // --sky, --view3d, --elmer, --patch-table
    // Memory for the reciprocity check and --enforce (a band of the transpose, and G); beyond it
    // scratch files.
    std::uint64_t stats_memory_bytes = std::uint64_t{512} << 20;
    // A .vs3's maxD (`ffcube view3d`, View3dCutoff): entries between patches whose
    // centroids lie farther apart removed from each row as it comes; 0: none.
    double max_distance = 0.0;
    bool object_factors = false;  // FormFactorFigures::object_factors wanted (--groups)
    // The patch reciprocity check (FormFactorFigures::reciprocity.patch_max_abs, report
    // "reciprocity.*"); off where nobody reads it (radiation of a sun series): no pass for it.
    bool reciprocity = true;
    bool progress = false;
};

struct FormFactorFigures {
    double seconds = 0;  // the rows (with coding and writing them)
    std::uint64_t nnz = 0;
    RowSumStats row_sums;
    ReciprocityStats reciprocity;
    std::vector<std::vector<double>> object_factors;  // as object_form_factors, when asked for
};

// Every row of F from `feed` (rows: the RowSource the feed's rows come from, for its options; each
// row's side figures are noted in its ledger as the row comes) into the output file named in `options`, Elmer's file and `sinks` (each
// fed the finished rows, enforced when rows.options().enforce asks, and finished), then the
// surface outputs. Report keys: "time.writing", "time.statistics", "ffm.bytes",
// "ffm.bytes_per_nnz", "reciprocity.*" (passes, bands, scratch_bytes), "enforce.*", "sky.*",
// "view3d.*". Not "seconds", "nnz", "row_sums.*": report_matrix_stats with the figures.
// Closure on an open scene: InputError (after the rows, nothing written).
FormFactorFigures compute_form_factors(const Scene& scene, RowSource& rows, RowFeed& feed,
                                       const FormFactorOptions& options, std::span<MatrixSink* const> sinks,
                                       Report& report);

// compute_form_factors of this process's rows (no checkpoint; options.output must be empty) into
// memory: the finished matrix (enforced when rows.options().enforce asks), its figures in *figures
// when given. Python's form_factors and radiate, `ffcube radiate` and `ffcube sun` take F this way.
CsrMatrix form_factor_matrix(const Scene& scene, RowSource& rows, Report& report, const FormFactorOptions& options = {},
                             FormFactorFigures* figures = nullptr);

}  // namespace ffcube
