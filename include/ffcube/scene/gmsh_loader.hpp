// FE and CAD meshes through Gmsh's library (Debian's libgmsh 4.8): Gmsh .msh 2.2 and 4.x (ASCII
// and binary), I-DEAS .unv, Nastran .bdf/.nas, legacy VTK .vtk, and STEP/IGES, which Gmsh meshes
// first (docs/fe-meshes.md). Gmsh runs in a guarded child process (core/guarded_child.hpp): a
// malformed file cannot crash or hang ffcube, and Gmsh's own errors come back as InputError
// naming the file.
//
// What becomes a face:
//  * surface elements (3- and 4-node, and the quadratic 6-, 8- and 9-node ones, split at their
//    mid-side nodes into linear triangles and quads so that curved geometry keeps its shape),
//    with their winding as written (counter-clockwise seen from the front);
//  * of volume elements (tetrahedra, hexahedra, prisms, pyramids, linear or quadratic), the
//    boundary faces only (faces of exactly one element), wound to face out of the material; a
//    surface element lying on such a face names it, a surface element on an internal face is
//    dropped.
// What names an object (FeObjectsBy): the physical surface group's name (an element in two
// groups is an error naming it; elements in none take `surface_<tag>` of their entity, with a
// warning; Nastran's PIDs become `pid_<n>`), the geometric entity, or each element alone.
#pragma once

#include <filesystem>
#include <string>
#include <string_view>
#include <vector>

#include "ffcube/scene/scene.hpp"

namespace ffcube {

enum class FeObjectsBy { group, entity, element };

struct FeLoadOptions {
    FeObjectsBy objects_by = FeObjectsBy::group;
    // Groups (object names) whose faces are reversed (--flip); a name that no face takes is an error.
    std::vector<std::string> flip;
    // A legacy .vtk's integer cell array whose values name the objects (--objects-by field:NAME,
    // vtk_legacy.hpp); empty: none.
    std::string field;
    // CAD files: the mesh size Gmsh meshes at (--max-patch-edge), or, when 0, the size that gives
    // about `cad_patches` squares of the model's area (--patches); both 0: Gmsh's default.
    double cad_mesh_size = 0.0;
    std::size_t cad_patches = 0;
};

// Whether the extension (".msh", "stp", any case) is read through Gmsh.
bool gmsh_reads_extension(std::string_view extension);
bool gmsh_is_cad_extension(std::string_view extension);

ObjModel load_with_gmsh(const std::filesystem::path& path, const FeLoadOptions& options = {});

// The pre-check of a Nastran bulk-data file that Gmsh would otherwise read in part without a
// word: every card is one Gmsh reads or one that carries no geometry; else InputError naming the
// file, the line and the card. Exposed for the tests and the fuzzer.
void check_nastran_cards(std::string_view text, const std::string& source);

// The pre-check of a .msh file's $PhysicalNames (Gmsh keeps the first of two groups of one name
// and drops the other name without a word): InputError naming the file and both lines.
void check_msh_physical_names(std::string_view bytes, const std::string& source);

}  // namespace ffcube
