// From SceneOptions to a meshed Scene: load (or take the built-in Cornell box), print warnings,
// mesh within this machine's memory, print the meshing summary, and record the figures and times
// in the report. Every front end loads through here.
#pragma once

#include <string_view>

#include "ffcube/io/report.hpp"
#include "ffcube/pipeline/options.hpp"
#include "ffcube/scene/assimp_loader.hpp"
#include "ffcube/scene/gmsh_loader.hpp"
#include "ffcube/scene/scene.hpp"

namespace ffcube {

Scene load_and_mesh(const SceneOptions& options, Report& report);

// The second half of load_and_mesh, for a model read elsewhere (Python's meshio.Mesh): materials
// (--materials), warnings, recentring, defect checks, contact cuts, meshing and the report, whose
// loading.format is `format`; `read_seconds`: the time the model took to read, for time.loading.
Scene mesh_model(ObjModel model, const SceneOptions& options, Report& report, std::string_view format, double read_seconds = 0.0,
                 const ImportedMaterials& imported = {});

// The options of a mesh read through Gmsh that SceneOptions carry (--objects-by, --flip, and the
// CAD mesh size of --max-patch-edge and --patches).
FeLoadOptions fe_load_options(const SceneOptions& options);

}  // namespace ffcube
