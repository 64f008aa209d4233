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

// Refuses an output path up front (before hours of work) when its directory does not exist.
void check_output_path(const std::string& option, const std::string& path);

}  // namespace ffcube::cli
