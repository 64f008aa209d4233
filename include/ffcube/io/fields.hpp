// Per-patch results back onto the mesh (`--fields OUT`, docs/fe-meshes.md): by the name's
// extension, a VTK XML unstructured grid for ParaView (.vtu, vtu.hpp) or a Gmsh model with one
// view per field (.msh, written through Gmsh's API).
//
// The .msh (format 4.1, ASCII) holds one discrete surface per object with a physical surface
// group of the object's name (a double quote written as a single one, which the format needs), the patches as 3-node triangles and 4-node quadrangles, and one
// view of "ElementData" per array, in the order and with the names the .vtu has: `patch`,
// `object`, `element_id` (when the scene came from a mesh read through Gmsh), `area`, then the
// fields given. A mesh element's tag is its element id when every patch has one and no two
// patches share one (a mesh read with --no-subdivide, linear elements); otherwise (subdivided
// patches, the linear pieces of a quadratic element, a scene with no ids) the tag is the patch's
// row + 1 and the id is in the view `element_id`. Node tags are 1 + the index of the vertex.
//
// Gmsh runs in a guarded child process (core/guarded_child.hpp), as for reading: its state and
// what it leaks at finalize stay out of ffcube's process. The child writes into a private
// temporary directory, and the file is then written atomically (atomic_file.hpp) at the path.
#pragma once

#include <filesystem>
#include <string>
#include <string_view>
#include <vector>

#include "ffcube/io/vtu.hpp"

namespace ffcube {

// InputError naming the option and the path when the path ends in neither .vtu nor .msh.
void check_fields_path(std::string_view option, const std::string& path);

// write_fields_vtu or write_fields_msh by the extension (checked by check_fields_path).
void write_fields(const std::filesystem::path& path, const Scene& scene, const std::vector<CellField>& fields);

void write_fields_msh(const std::filesystem::path& path, const Scene& scene, const std::vector<CellField>& fields);

}  // namespace ffcube
