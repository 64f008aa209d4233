// PLY, glTF 2.0 (.gltf/.glb) and the other formats Debian's assimp imports. Imported with
// aiProcess_JoinIdenticalVertices only (quads and n-gons stay as they are: the mesher decides);
// node transforms are applied (a mirroring one reverses the winding back). Objects are named by
// the node (else the mesh, else "mesh<k>"); every face gets the default material. Points and
// lines are skipped with a warning; coordinates must be finite with magnitude at most 1e15.
#pragma once

#include <filesystem>
#include <string_view>

#include "ffcube/scene/scene.hpp"

namespace ffcube {

// Whether assimp has an importer for this extension (".ply", "gltf", ...).
bool assimp_reads_extension(std::string_view extension);

ObjModel load_with_assimp(const std::filesystem::path& path);

}  // namespace ffcube
