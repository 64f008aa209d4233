// Pieces shared by the ffcube subcommands: the scene and form-factor options, loading and
// meshing a scene, and starting a row provider. Thin: the work is in the library layers.
#pragma once

#include <CLI/CLI.hpp>

#include <filesystem>
#include <memory>
#include <optional>
#include <string>

#include "ffcube/gl/hemicube_provider.hpp"
#include "ffcube/io/report.hpp"
#include "ffcube/scene/mesher.hpp"
#include "ffcube/scene/scene.hpp"

namespace ffcube::cli {

struct SceneOptions {
    std::string scene;  // empty: the built-in Cornell box
    double max_patch_edge = 0.0;
    std::size_t patches = 0;
    bool quiet = false;
};

struct FormFactorOptions {
    int resolution = 256;
    std::string backend = "auto";
    unsigned threads = 0;
    bool no_rotate = false;
    std::uint64_t seed = 0x5eed;
};

void add_scene_options(CLI::App& app, SceneOptions& o);
void add_formfactor_options(CLI::App& app, FormFactorOptions& o);

// Loads (or takes the built-in scene), prints warnings, meshes, prints the meshing summary.
// Records meshing figures and its time in the report.
Scene load_and_mesh(const SceneOptions& o, Report& report);

HemicubeOptions hemicube_options(const FormFactorOptions& o);

// Refuses an output path up front (before hours of work) when its directory does not exist.
void check_output_path(const std::string& option, const std::string& path);

}  // namespace ffcube::cli
