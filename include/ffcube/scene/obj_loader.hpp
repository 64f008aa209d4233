// Wavefront OBJ + MTL input. Strict about what matters (indices, numbers, face sizes, Kd/Ke
// ranges) and lenient about the rest (CRLF, BOM, tabs, no final newline, vt/vn, unknown
// statements). Every refusal throws InputError naming file, line and the rule broken.
#pragma once

#include <filesystem>
#include <functional>
#include <optional>
#include <string>
#include <string_view>

#include "ffcube/scene/gmsh_loader.hpp"
#include "ffcube/scene/scene.hpp"

namespace ffcube {

// Reads an MTL library named by 'mtllib'; returns nullopt when it cannot be found (a warning,
// not an error: materials then get the default).
using MtlResolver = std::function<std::optional<std::string>(const std::string& name)>;

// What names a face's object (docs/scene-format.md, "Objects"). auto: 'o' when the file has any
// 'o', else 'g' when it has any 'g', else the material ('usemtl'). The others take that statement
// only, for files whose groups do not follow their faces (some Cornell box files list a box's
// faces before its 'g' line, with one material per box). Faces before the first such statement
// belong to the object "default".
enum class ObjObjectsBy { automatic, o, g, material };

// "auto", "o", "g" or "material"; anything else is an InputError naming 'option'.
ObjObjectsBy parse_objects_by(std::string_view name, std::string_view option = "--objects-by");

struct ObjLoadOptions {
    ObjObjectsBy objects_by = ObjObjectsBy::automatic;
    FeLoadOptions fe;  // meshes and CAD read through Gmsh (gmsh_loader.hpp)
};

// Parses OBJ text. 'source' names it in messages.
ObjModel parse_obj(std::string_view text, const std::string& source, const MtlResolver& mtl,
                   const ObjLoadOptions& options = {});

// Loads an OBJ file; MTL files are looked up relative to the OBJ's directory.
ObjModel load_obj(const std::filesystem::path& path, const ObjLoadOptions& options = {});

// Parses MTL text into materials appended to 'out' (name → Kd, Ke); 'source' names it in messages.
void parse_mtl(std::string_view text, const std::string& source, std::vector<Material>& out);

}  // namespace ffcube
