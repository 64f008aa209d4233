// Pieces shared by the ffcube subcommands: the scene and form-factor options, loading and
// meshing a scene, and starting a row provider. Thin: the work is in the library layers.
#pragma once

#include <CLI/CLI.hpp>

#include <filesystem>
#include <memory>
#include <optional>
#include <string>

#include "ffcube/accuracy/near_field.hpp"
#include "ffcube/formfactor/sparse.hpp"
#include "ffcube/gl/hemicube_provider.hpp"
#include "ffcube/io/ffm.hpp"
#include "ffcube/raycast/raycast_provider.hpp"
#include "ffcube/io/report.hpp"
#include "ffcube/scene/mesher.hpp"
#include "ffcube/scene/scene.hpp"

namespace ffcube::cli {

struct SceneOptions {
    std::string scene;  // empty: the built-in Cornell box
    double max_patch_edge = 0.0;
    std::size_t patches = 0;
    std::string objects_by = "auto";  // --objects-by: auto, o, g or material (ObjObjectsBy)
    bool quiet = false;
};

struct FormFactorOptions {
    std::string method = "hemicube";  // or "raycast" (Monte Carlo through Embree, no GL)
    int resolution = 256;
    std::string backend = "auto";
    unsigned threads = 0;
    bool no_rotate = false;
    std::uint64_t seed = 0x5eed;
    std::uint64_t rays = 4096;  // raycast: rays per patch
    // "none" or "near": near-field analytic correction (docs/accuracy.md), with sender
    // quadrature for the hemicube's other entries.
    std::string correct = "near";
    double near_k = 3.0;
    std::string far_field = "auto";  // auto, on or off
    std::string enforce;  // formfactors only: "", reciprocity, closure or both
};

// Where rows come from: hemicubes on a GL context, or rays through Embree.
struct RowSource {
    std::unique_ptr<HemicubeRowProvider> hemicube;
    std::unique_ptr<RaycastRowProvider> raycast;
    std::unique_ptr<CorrectedRowProvider> corrected;  // wraps one of the two (--correct near)
    RowProvider& provider() {
        if (corrected) return *corrected;
        return hemicube ? static_cast<RowProvider&>(*hemicube) : *raycast;
    }
};

void add_scene_options(CLI::App& app, SceneOptions& o);
void add_formfactor_options(CLI::App& app, FormFactorOptions& o);
// --enforce (formfactors only: it acts on the finished matrix).
void add_enforce_option(CLI::App& app, FormFactorOptions& o);

// Loads (or takes the built-in scene), prints warnings, meshes, prints the meshing summary.
// Records meshing figures and its time in the report.
Scene load_and_mesh(const SceneOptions& o, Report& report);

HemicubeOptions hemicube_options(const FormFactorOptions& o);

// How rows are made, as recorded in .ffm files and checkpoints (deterministic settings only).
FfmMetadata row_metadata(const FormFactorOptions& o);

// Validates the options (throws InputError) and starts the provider they name, printing what it
// runs on and recording its setup time. Start it before this process makes a GL context of its
// own, so that hemicube workers can be forked processes.
RowSource make_row_source(const Scene& scene, const FormFactorOptions& o, Report& report);

// The provider's figures: backend, renderer, resolution, workers, time split and culling for
// hemicubes; rays for the ray caster.
void report_row_source(Report& report, const RowSource& rows);

// --enforce: reciprocity/closure on the finished matrix, with before/after figures in the report
// ("enforce.*"). Refused (InputError) for open scenes: a hemicube pixel that saw nothing, or a row
// summing below 1 − 1e-3. Returns F unchanged when no --enforce was given.
CsrMatrix apply_enforcement(const FormFactorOptions& o, CsrMatrix F, const Scene& scene, const RowSource& rows,
                            Report& report);

// Refuses an output path up front (before hours of work) when its directory does not exist.
void check_output_path(const std::string& option, const std::string& path);

}  // namespace ffcube::cli
