// Computing every row of F through a provider, optionally through a checkpoint directory
// (--checkpoint DIR [--resume], see docs/robustness.md): the command-line side of
// ffcube/io/checkpoint.hpp.
#pragma once

#include <functional>
#include <optional>
#include <string>

#include <CLI/CLI.hpp>

#include "ffcube/formfactor/row_provider.hpp"
#include "ffcube/io/checkpoint.hpp"
#include "ffcube/io/report.hpp"
#include "ffcube/scene/scene.hpp"

namespace ffcube::cli {

struct CheckpointOptions {
    std::string dir;  // empty: no checkpoint
    bool resume = false;
};

// Adds --checkpoint DIR and --resume (which needs --checkpoint).
void add_checkpoint_options(CLI::App& app, CheckpointOptions& o);

// What a checkpoint of this scene's rows made with these settings records (and resuming compares).
CheckpointManifest checkpoint_manifest(const Scene& scene, const FfmMetadata& meta);

// Opens the checkpoint (create, or resume: validated against this scene and these settings)
// before any expensive setup, so that a mismatch is refused at once. nullopt without --checkpoint.
// Warnings about a damaged log are logged; rows reused are recorded in the report.
std::optional<RowCheckpoint> open_checkpoint(const CheckpointOptions& o, const Scene& scene, const FfmMetadata& meta,
                                             Report& report);

// Every row of F. Without a checkpoint, rows go straight into the matrix. With one, only the rows
// missing from it are computed, each appended to the log as it comes, and the matrix is then read
// back from the log in row order: bit-identical to an uninterrupted run. obstructed: the
// provider's per-row obstructed shares (RowSource::obstructed(), set before each row reaches the
// sink; empty without obstruction-only surfaces), stored with each row in the checkpoint, whose
// obstructed() then holds every row's, reused or computed.
CsrMatrix compute_matrix(RowProvider& provider, RowCheckpoint* checkpoint, bool progress,
                         std::span<const double> obstructed = {});

// The same rows, each handed to sink in row order as the float row CsrMatrix would hold
// (bit-identical to compute_matrix's), without holding the matrix: straight from the provider,
// or, with a checkpoint, the missing rows computed into the log and then every row read back
// from it one at a time.
void stream_rows(RowProvider& provider, RowCheckpoint* checkpoint, bool progress,
                 const std::function<void(std::uint32_t, RowView)>& sink, std::span<const double> obstructed = {});

}  // namespace ffcube::cli
