// The flags every subcommand shares, parsed straight into the library's option structs
// (pipeline/options.hpp): the scene, how rows are made, and output-path checks. Thin: loading,
// the row pipeline and every policy live in the library layers.
#pragma once

#include <CLI/CLI.hpp>

#include <cstdint>
#include <string>

#include "ffcube/pipeline/options.hpp"

namespace ffcube::cli {

// The scene flags, and --quiet (which the subcommand applies before its work).
struct SceneFlags {
    SceneOptions scene;
    bool quiet = false;
};

void add_scene_options(CLI::App& app, SceneFlags& o);
// --method, --resolution, --backend, --threads, --no-rotate, --seed, --rays, --correct,
// --near-k, --far-field.
void add_row_options(CLI::App& app, RowOptions& o);
// --enforce (formfactors only: it acts on the finished matrix).
void add_enforce_option(CLI::App& app, RowOptions& o);

// Shooters asked from the row provider per call (SolverOptions::batch) by solve and view: enough
// to keep 16 hemicube workers busy. Fixed rather than the thread count, because the shooting order
// (and so B in its last digits) depends on the batch, and results must not depend on the thread
// count. The viewer once used one per worker, and its workers idled between batches (108 shots/s
// against solve's 134 rows/s, docs/benchmarks.md).
inline constexpr std::uint32_t kShotBatch = 16;

// Refuses an output path up front (before hours of work) when its directory does not exist.
void check_output_path(const std::string& option, const std::string& path);

}  // namespace ffcube::cli
