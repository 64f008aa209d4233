// Legacy VTK files (.vtk) read by ffcube itself, for what Gmsh 4.8's VTK reader cannot do: an
// integer cell array as the objects (`--objects-by field:NAME`), and files of version 5.x (the
// OFFSETS/CONNECTIVITY cells that ParaView and meshio write by default, which Gmsh 4.8 misreads
// or crashes on). The cells become FeCells (fe_cells.hpp), which the same code as a mesh read
// through Gmsh turns into faces (docs/fe-meshes.md, "VTK groups").
//
// Read: versions 1.0 to 5.1, ASCII and BINARY (big-endian), DATASET UNSTRUCTURED_GRID; POINTS,
// CELLS (counts and ids up to version 4.2; OFFSETS and CONNECTIVITY from 5.0), CELL_TYPES, and
// the attributes of CELL_DATA and POINT_DATA (SCALARS with their LOOKUP_TABLE, FIELD arrays,
// VECTORS, NORMALS, TENSORS, TEXTURE_COORDINATES, COLOR_SCALARS, LOOKUP_TABLE), METADATA blocks
// skipped. Cells: VTK's linear and quadratic triangles, quads, tetrahedra, hexahedra, wedges and
// pyramids (in meshio's names and node order); vertices and lines are skipped; any other type is
// refused naming the cell. A cell's element id is 1 + its index in the file.
//
// Objects: with `field` non-empty, the integer cell array of that name (a SCALARS or FIELD array
// of one component in CELL_DATA) names every cell `<field>_<value>`, as
// load_scene(meshio.read(...), objects_by="field:NAME") names them in Python. Without it, every
// cell is in no group, on one geometric entity per dimension (`surface_1`), as Gmsh reads a .vtk.
//
// Every malformed file is an InputError naming the file, the line (ASCII) or byte (binary data),
// and the rule: a count the file cannot hold, a number that is not one, a cell that names a
// point that does not exist, a keyword ffcube does not read, a missing or non-integer field.
#pragma once

#include <string>
#include <string_view>

#include "ffcube/scene/fe_cells.hpp"

namespace ffcube {

// The major version of a legacy VTK file from its first line ("# vtk DataFile Version 5.1"), or
// -1 when the bytes do not begin so.
int vtk_legacy_version(std::string_view bytes);

FeCells read_vtk_legacy(std::string_view bytes, const std::string& source, const std::string& field);

}  // namespace ffcube
