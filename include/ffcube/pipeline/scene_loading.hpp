// From SceneOptions to a meshed Scene: load (or take the built-in Cornell box), print warnings,
// mesh within this machine's memory, print the meshing summary, and record the figures and times
// in the report. Every front end loads through here.
#pragma once

#include "ffcube/io/report.hpp"
#include "ffcube/pipeline/options.hpp"
#include "ffcube/scene/scene.hpp"

namespace ffcube {

Scene load_and_mesh(const SceneOptions& options, Report& report);

}  // namespace ffcube
