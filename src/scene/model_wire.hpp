// An imported ObjModel (and the ImportedMaterials counts) as bytes, for the way back from the
// child process that runs assimp (assimp_loader.cpp). Doubles travel as their bits, so the parent
// gets exactly what the child computed. The reader trusts nothing: the child ran a parser on
// hostile bytes, so every length is checked against the bytes left and every index against its
// array (InternalError: a child of the same binary that writes a bad frame is a bug, or memory
// corruption in the child).
#pragma once

#include <string>
#include <string_view>

#include "ffcube/scene/assimp_loader.hpp"
#include "ffcube/scene/scene.hpp"

namespace ffcube::detail {

// The fields an importer fills: source, positions, faces, objects, materials, warnings,
// dropped_degenerate, merged_vertices (not view3d, not obstruction_objects: always empty here).
std::string encode_imported(const ObjModel& model, const ImportedMaterials& materials);
ObjModel decode_imported(std::string_view bytes, ImportedMaterials& materials);

}  // namespace ffcube::detail
