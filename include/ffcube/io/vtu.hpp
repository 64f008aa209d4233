// Per-patch fields on the meshed scene as a VTK XML UnstructuredGrid (.vtu, ASCII), for ParaView
// and for meshio (docs/fe-meshes.md, "Results back into ParaView"). Written by ffcube itself (no
// VTK library): one cell per patch (VTK_TRIANGLE 5 or VTK_QUAD 9), the patch's vertices in the
// user's coordinates (Scene::origin added back), and as cell data: `patch` (the row index),
// `object` (index into the scene's objects, in the order of their first patch in
// the patch table; meshio cannot read VTK's string arrays, so the names are not in the file), `area`, `element_id` (when the scene came from a mesh read through Gmsh) and every
// field given. Written atomically (io/atomic_file.hpp).
#pragma once

#include <filesystem>
#include <span>
#include <string>
#include <utility>
#include <vector>

#include "ffcube/scene/scene.hpp"

namespace ffcube {

struct CellField {
    std::string name;
    std::span<const double> values;  // one per patch
};

void write_fields_vtu(const std::filesystem::path& path, const Scene& scene, const std::vector<CellField>& fields);

}  // namespace ffcube
