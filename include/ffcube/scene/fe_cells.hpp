// A mesh given as arrays rather than a file (Python's meshio.Mesh: ffcube.load_scene(mesh)),
// read by the same code as a mesh file read through Gmsh (gmsh_loader.hpp): the cells are handed
// to Gmsh's model API in a guarded child, and the same collector makes the faces, so quadratic
// cells are split, volume cells radiate from their boundary faces, facing out, and groups name
// objects as for a .msh file (docs/fe-meshes.md, "From Python and meshio").
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "ffcube/scene/gmsh_loader.hpp"

namespace ffcube {

// One block of cells of one type, in meshio's names and node order (VTK's).
struct FeCellBlock {
    std::string type;                  // "triangle", "quad", "tetra", "hexahedron20", ...; "vertex", "line*": skipped
    std::size_t width = 0;             // nodes per cell
    std::vector<std::int64_t> nodes;   // cells x width, 0-based indices into FeCells::points
    std::vector<std::int32_t> group;   // per cell: index into FeCells::groups, -1: in no group; empty: none in a group
    std::vector<std::int64_t> entity;  // per cell: its geometric entity (gmsh:geometrical); empty: the block is one

    std::size_t cells() const { return width == 0 ? 0 : nodes.size() / width; }
};

struct FeCells {
    std::string source = "meshio.Mesh";  // for messages
    std::vector<Vec3> points;
    std::vector<FeCellBlock> blocks;
    std::vector<std::string> groups;  // distinct, non-empty names
};

// Whether ffcube reads cells of this meshio type (surface or volume), skips it (vertex, line*),
// or neither (then load_fe_cells refuses the block).
enum class FeCellKind { read, skipped, unknown };
FeCellKind fe_cell_kind(const std::string& meshio_type);

// The faces of the cells; a cell's element id is 1 + its index counted over all blocks in order
// (the order of meshio's mesh.cells, skipped blocks included). InputError naming the block, the
// cell and the rule for an unknown cell type, a wrong width, a point index out of range or a
// point that is not finite.
ObjModel load_fe_cells(const FeCells& cells, const FeLoadOptions& options);

}  // namespace ffcube
