// The flags of the outputs other tools read (pipeline/surface_outputs.hpp): --sky, --sky-by,
// --view3d, --view3d-format, --elmer, --elmer-format, --patch-table.
#pragma once

#include <CLI/CLI.hpp>

#include "ffcube/pipeline/surface_outputs.hpp"

namespace ffcube::cli {

void add_surface_output_options(CLI::App& app, SurfaceOutputOptions& o);
// Only --sky and --sky-by (ffcube solve: the same file and report keys as formfactors').
void add_sky_options(CLI::App& app, SurfaceOutputOptions& o);
// Refuses an output whose directory is missing, before any work (check_output_path).
void check_surface_output_paths(const SurfaceOutputOptions& o);

}  // namespace ffcube::cli
