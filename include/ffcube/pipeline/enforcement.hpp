// --enforce on the finished rows (pipeline/form_factors.hpp's one path), out of core: the rows as
// computed are read again by passes (from a scratch .ffm, or from memory when no file is written),
// never held as a matrix here. The accuracy layer's enforce_passes does the arithmetic
// (accuracy/enforce.hpp).
#pragma once

#include <cstdint>
#include <filesystem>
#include <functional>
#include <span>

#include "ffcube/accuracy/enforce.hpp"
#include "ffcube/formfactor/checks.hpp"
#include "ffcube/io/report.hpp"
#include "ffcube/pipeline/row_source.hpp"
#include "ffcube/scene/scene.hpp"

namespace ffcube {

// Closure cannot hold where obstruction-only (O) surfaces absorb energy without rows or columns
// (docs/scene-format.md): InputError naming the scene. Called before any row is computed, and by
// apply_enforcement.
void refuse_enforcement_with_obstructions(EnforceRequest request, const Scene& scene);

// What the providers saw of whether the scene is closed (hemicube pixels that saw nothing, the
// smallest row sum before correction), judged by --enforce closure. Under mpirun a rank's
// providers saw only its rows: the ranks' evidence is reduced onto rank 0 (src/cli/mpi_glue.cpp).
ClosureEvidence closure_evidence(const RowSource& rows);

struct EnforcementFigures {
    std::size_t passes = 0;         // over the unenforced rows' file
    std::size_t bands = 0;          // column bands of its transpose
    std::size_t g_passes = 0;       // closure: passes over G (one per iteration, and one more)
    bool g_on_disk = false;         // closure: G did not fit budget_bytes and went to a scratch file
    std::uint64_t scratch_bytes = 0;
    // ReciprocityStats::patch_max_abs of the float rows handed to the sink (what reciprocity_stats
    // gives for them in memory): the enforced matrix's F_ji is computed with F_ij, G being symmetric.
    double patch_max_abs = 0;
};

// --enforce (options.enforce, not None) on the rows `raw` gives (a pass over the rows as computed,
// in order, any number of times); raw_checks and raw_row_sums are from the same rows
// (RowStreamChecks, and RowView::sum per row: closure is refused, InputError, for an open scene
// judged on `evidence`, the closure evidence of every row, and on those sums).
// Each enforced row goes to sink in row order, as float (the rows are computed in double).
// Scratch files go to scratch_dir; memory: budget_bytes for a band of the transpose and for G
// (closure; beyond it G goes to a scratch file, read once per iteration), plus O(n). Report keys
// "enforce.*": mode, before/after row sums and reciprocity, iterations, seconds, passes, bands,
// g_passes, scratch_bytes.
EnforcementFigures apply_enforcement(const RowOptions& options, const RowPass& raw, const RowStreamChecks& raw_checks,
                                     std::span<const double> raw_row_sums, const Scene& scene,
                                     const ClosureEvidence& evidence, const std::filesystem::path& scratch_dir,
                                     std::uint64_t budget_bytes, bool progress,
                                     const std::function<void(std::uint32_t, RowView)>& sink, Report& report);

}  // namespace ffcube
