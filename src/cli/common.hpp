// The flags every subcommand shares, parsed straight into the library's option structs
// (pipeline/options.hpp): the scene, how rows are made, and output-path checks. Thin: loading,
// the row pipeline and every policy live in the library layers.
#pragma once

#include <CLI/CLI.hpp>

#include <cstdint>
#include <span>
#include <string>

#include "ffcube/pipeline/adaptive.hpp"
#include "ffcube/pipeline/form_factors.hpp"
#include "ffcube/pipeline/options.hpp"
#include "ffcube/scene/scene.hpp"

namespace ffcube::cli {

// --target-error, --max-elements (solve and view; docs/adaptive.md): adaptive meshing, on when
// either is given.
struct AdaptiveFlags {
    AdaptiveOptions options;
    CLI::Option* target_error = nullptr;
    CLI::Option* max_elements = nullptr;
    bool on() const { return (target_error && target_error->count() > 0) || (max_elements && max_elements->count() > 0); }
};
void add_adaptive_options(CLI::App& app, AdaptiveFlags& o);
// When on: validates the options and, when the command line names no mesh (--patches,
// --max-patch-edge), starts from the coarse mesh of kAdaptiveStartPatches.
void prepare_adaptive(const AdaptiveFlags& o, SceneOptions& scene);

// The scene flags, and --quiet (which the subcommand applies before its work).
struct SceneFlags {
    SceneOptions scene;
    bool quiet = false;
};

void add_scene_options(CLI::App& app, SceneFlags& o);
// --method, --resolution, --backend, --threads, --no-rotate, --seed, --rays, --correct,
// --near-k, --far-field.
// The rows' accuracy target: `--tolerance` (formfactors, view3d), or behind the expert door as
// `--row-tolerance` where --tolerance is the solver's (solve, view, radiate).
enum class RowTolerance { main, expert };
void add_row_options(CLI::App& app, RowOptions& o, RowTolerance tolerance = RowTolerance::main);
// --far-field-emitters on|off (solve and view; on by default): RowOptions::far_field_emitters.
void add_far_field_emitters_option(CLI::App& app, RowOptions& o);
// --enforce (formfactors only: it acts on the finished matrix).
void add_enforce_option(CLI::App& app, RowOptions& o);
// Adds --checkpoint DIR and --resume (which needs --checkpoint).
void add_checkpoint_options(CLI::App& app, CheckpointOptions& o);

// Writes the area-weighted mean radiosity per object of `scene` (io/csv.hpp's object CSV,
// atomically): solve --objects and view --objects.
void write_objects_csv(const std::string& path, const Scene& scene, std::span<const Vec3> radiosity);

// Refuses an output path up front (before hours of work) when its directory does not exist.
void check_output_path(const std::string& option, const std::string& path);

}  // namespace ffcube::cli
