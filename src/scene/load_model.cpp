// The format dispatcher: one ObjModel from any scene file ffcube reads.
#include "ffcube/scene/load_model.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cctype>

#include "ffcube/core/error.hpp"
#include "ffcube/core/input_file.hpp"
#include "ffcube/scene/assimp_loader.hpp"
#include "ffcube/scene/gmsh_loader.hpp"
#include "ffcube/scene/obj_loader.hpp"
#include "ffcube/scene/stl_loader.hpp"
#include "ffcube/scene/vs3_loader.hpp"

namespace ffcube {

SceneFormat parse_scene_format(std::string_view word) {
    if (word == "auto") return SceneFormat::Auto;
    if (word == "obj") return SceneFormat::Obj;
    if (word == "stl") return SceneFormat::Stl;
    if (word == "vs3") return SceneFormat::View3d;
    if (word == "assimp" || word == "ply" || word == "gltf" || word == "glb") return SceneFormat::Assimp;
    if (word == "gmsh" || (word != "gmsh" && gmsh_reads_extension(word))) return SceneFormat::Gmsh;
    throw InputError(fmt::format("--format {}: unknown format (auto, obj, stl, vs3, ply, gltf, glb, assimp, msh, unv, bdf, nas, "
                                 "vtk, step, stp, iges, igs or gmsh)",
                                 word));
}

std::string_view to_string(SceneFormat f) {
    switch (f) {
    case SceneFormat::Auto: return "auto";
    case SceneFormat::Obj: return "obj";
    case SceneFormat::Stl: return "stl";
    case SceneFormat::View3d: return "vs3";
    case SceneFormat::Assimp: return "assimp";
    case SceneFormat::Gmsh: return "gmsh";
    }
    return "?";
}

SceneFormat format_for_path(const std::filesystem::path& path) {
    std::string ext = path.extension().string();
    std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
    if (ext == ".obj") return SceneFormat::Obj;
    if (ext == ".stl") return SceneFormat::Stl;
    if (ext == ".vs3") return SceneFormat::View3d;
    if (gmsh_reads_extension(ext)) return SceneFormat::Gmsh;
    if (!ext.empty() && assimp_reads_extension(ext)) return SceneFormat::Assimp;
    // No extension, or one nobody reads: OBJ, as ffcube has always read it (its messages then say
    // "is this an OBJ file?"; --format names another format).
    return SceneFormat::Obj;
}

ObjModel load_model(const std::filesystem::path& path, SceneFormat format, const ObjLoadOptions& obj,
                    ImportedMaterials* materials) {
    if (format == SceneFormat::Auto) {
        std::string ext = path.extension().string();
        std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
        // Gmsh 4.8 reads legacy .vtk only, and without its cell data; meshio reads VTK XML and its
        // arrays, so the route is Python's (docs/fe-meshes.md, "From Python and meshio").
        if (ext == ".vtu" || ext == ".pvtu" || ext == ".vtp")
            throw InputError(fmt::format("{}: VTK XML ({}) is not read by the command line (Gmsh reads legacy .vtk only, without "
                                         "its cell data); in Python, ffcube.load_scene(meshio.read(\"{}\"), "
                                         "objects_by=\"field:NAME\") reads it with an integer cell array NAME as the groups "
                                         "(docs/fe-meshes.md)",
                                         path.string(), ext, path.string()));
        format = format_for_path(path);
    }
    if (format != SceneFormat::Gmsh && !obj.fe.flip.empty())
        throw InputError(fmt::format("{}: --flip {}: --flip reverses groups of a mesh read through Gmsh (.msh, .unv, .bdf, .nas, "
                                     ".vtk, .step, .iges); this file is read as {}",
                                     path.string(), obj.fe.flip.front(), to_string(format)));
    if (!obj.fe.field.empty() && (format != SceneFormat::Gmsh || path.extension() != ".vtk"))
        throw InputError(fmt::format("{}: --objects-by field:{} names objects by an integer cell array of a legacy VTK file (.vtk); "
                                     "this file is read as {}{}",
                                     path.string(), obj.fe.field, to_string(format),
                                     format == SceneFormat::Gmsh ? " (its groups: --objects-by group, entity or element)" : ""));
    if (format != SceneFormat::Gmsh && obj.fe.objects_by != FeObjectsBy::group)
        throw InputError(fmt::format("{}: --objects-by entity and element apply to meshes read through Gmsh; this file is read "
                                     "as {} (its words: auto, o, g, material)",
                                     path.string(), to_string(format)));
    if (format == SceneFormat::Gmsh && obj.objects_by != ObjObjectsBy::automatic)
        throw InputError(fmt::format("{}: --objects-by o, g and material apply to OBJ files; a mesh read through Gmsh takes "
                                     "group, entity or element",
                                     path.string()));
    switch (format) {
    case SceneFormat::Obj: return load_obj(path, obj);
    case SceneFormat::Stl: return load_stl(path);
    case SceneFormat::View3d: return load_vs3(path);
    case SceneFormat::Assimp: return load_with_assimp(path, materials);
    case SceneFormat::Gmsh: return load_with_gmsh(path, obj.fe);
    case SceneFormat::Auto: break;
    }
    throw InternalError("load_model: no format");
}

std::string read_scene_file(const std::filesystem::path& path, const char* kind, const char* role) {
    return read_input_file(path, kind, role);
}

}  // namespace ffcube
