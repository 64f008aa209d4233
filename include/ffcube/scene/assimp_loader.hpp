// PLY, glTF 2.0 (.gltf/.glb) and the other formats Debian's assimp imports. Imported with
// aiProcess_JoinIdenticalVertices only (quads and n-gons stay as they are: the mesher decides);
// node transforms are applied (a mirroring one reverses the winding back). Objects are named by
// the node (else the mesh, else "mesh<k>"). Materials (a mesh's material, so per face: assimp
// splits meshes by material) map to Kd and Ke as an MTL's would: Kd = the diffuse colour (glTF:
// baseColorFactor), times the mean of the face's vertex colours when the mesh has them; Ke = the
// emissive colour (glTF: emissiveFactor). Faces without a material of the file get OBJ's default;
// textures are ignored (a warning says so); ImportedMaterials counts it all. Points and
// lines are skipped with a warning; coordinates must be finite with magnitude at most 1e15.
#pragma once

#include <cstddef>
#include <filesystem>
#include <string_view>

#include "ffcube/scene/scene.hpp"

namespace ffcube {

// What the reader made of a file's materials (docs/scene-format.md, "Materials through assimp");
// reported under loading.materials.
struct ImportedMaterials {
    bool present = false;                 // the scene was read through assimp
    std::size_t from_file = 0;            // materials the file defines (assimp's own default not counted)
    std::size_t faces_material = 0;       // faces whose Kd/Ke come from the file's material
    std::size_t faces_vertex_colour = 0;  // faces whose Kd is the mean of their vertex colours (× the material's)
    std::size_t faces_default = 0;        // faces with no material of the file: OBJ's default (Kd 0.5, Ke 0)
    std::size_t textured = 0;             // materials with colour textures: ignored, their colour factor used
};

// Whether assimp has an importer for this extension (".ply", "gltf", ...).
bool assimp_reads_extension(std::string_view extension);

// `materials`, when given, receives the counts above.
ObjModel load_with_assimp(const std::filesystem::path& path, ImportedMaterials* materials = nullptr);

}  // namespace ffcube
