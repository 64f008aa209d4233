// Scene input in every format ffcube reads, as one ObjModel (scene.hpp): Wavefront OBJ/MTL
// (obj_loader.hpp), STL ASCII and binary (stl_loader.hpp), NIST View3D .vs3 (vs3_loader.hpp) and,
// through Debian's assimp, PLY, glTF 2.0 and the other formats assimp imports. The format comes
// from the file's extension, or is given (the CLI's --format). docs/scene-format.md describes
// what each reader takes and refuses.
#pragma once

#include <filesystem>
#include <string>
#include <string_view>

#include "ffcube/scene/assimp_loader.hpp"
#include "ffcube/scene/obj_loader.hpp"
#include "ffcube/scene/scene.hpp"

namespace ffcube {

enum class SceneFormat { Auto, Obj, Stl, View3d, Assimp, Gmsh };

// "auto", "obj", "stl", "vs3", "assimp" (also "ply", "gltf", "glb": read through assimp), "gmsh"
// (also "msh", "unv", "bdf", "nas", "vtk", "step", "stp", "iges", "igs": read through Gmsh).
// Throws InputError naming --format and the words it accepts.
SceneFormat parse_scene_format(std::string_view word);
std::string_view to_string(SceneFormat f);

// The format an extension names (case-insensitive): .stl, .vs3, else assimp when assimp imports
// that extension (Gmsh's extensions first: gmsh_loader.hpp); .obj, no extension and unknown extensions are read as OBJ (as before formats).
SceneFormat format_for_path(const std::filesystem::path& path);

// Loads a scene file in the given format (Auto: by extension).
// obj: how an OBJ file names its objects (--objects-by); other formats name theirs themselves.
// materials: filled (present = true) when the file was read through assimp.
ObjModel load_model(const std::filesystem::path& path, SceneFormat format = SceneFormat::Auto,
                    const ObjLoadOptions& obj = {}, ImportedMaterials* materials = nullptr);

// Reads a scene file into memory (core/input_file.hpp: regular files only, checked before
// opening): InputError naming the file when it is missing, a directory, a FIFO or device, or
// unreadable. 'kind' names the format in messages ("an STL file"), 'role' the input.
std::string read_scene_file(const std::filesystem::path& path, const char* kind, const char* role = "the scene");

}  // namespace ffcube
