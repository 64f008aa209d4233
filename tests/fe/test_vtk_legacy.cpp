// ffcube's legacy VTK reader (scene/vtk_legacy.hpp), in process, on files written here by hand
// from the VTK file-format document: the same mesh in ASCII and BINARY (big-endian, written
// byte by byte here), versions 4.2 and 5.1, gives the same points, cells, node order and groups;
// every malformed file is refused naming the file, the line or byte, and the rule.
#include <gtest/gtest.h>

#include <cstdint>
#include <cstring>
#include <string>
#include <vector>

#include "ffcube/core/error.hpp"
#include "ffcube/scene/vtk_legacy.hpp"

namespace ffcube {
namespace {

std::string refusal(const std::string& bytes, const std::string& field = "g") {
    try {
        read_vtk_legacy(bytes, "m.vtk", field);
    } catch (const InputError& e) {
        return e.what();
    }
    return "";
}

// A quad (points 0-3), a vertex (point 4), a triangle (0, 1, 4) and a wedge (VTK order 0..5 on
// points 5-10): the cell array "g" = 7, 9, 8, 7 and a float array "t" before it.
const char* kPoints = "0 0 0 1 0 0 1 1 0 0 1 0 0.5 0.5 1 0 0 2 1 0 2 0 1 2 0 0 3 1 0 3 0 1 3";

std::string ascii42() {
    return std::string("# vtk DataFile Version 4.2\ntitle\nASCII\nDATASET UNSTRUCTURED_GRID\nPOINTS 11 double\n") + kPoints +
           "\nCELLS 4 18\n4 0 1 2 3\n1 4\n3 0 1 4\n6 5 6 7 8 9 10\nCELL_TYPES 4\n9 1 5 13\n"
           "CELL_DATA 4\nSCALARS t float 1\nLOOKUP_TABLE default\n0.5 1.5 2.5 3.5\nFIELD FieldData 1\ng 1 4 int\n7 9 8 7\n";
}

void put(std::string& s, std::uint64_t v, int bytes) {
    for (int k = bytes - 1; k >= 0; --k) s += char((v >> (8 * k)) & 0xff);
}
void put_double(std::string& s, double d) {
    std::uint64_t u;
    std::memcpy(&u, &d, 8);
    put(s, u, 8);
}

std::string binary51() {
    std::string s = "# vtk DataFile Version 5.1\nvtk output\nBINARY\nDATASET UNSTRUCTURED_GRID\nPOINTS 11 double\n";
    const double p[33] = {0, 0, 0, 1, 0, 0, 1, 1, 0, 0, 1, 0, 0.5, 0.5, 1, 0, 0, 2, 1, 0, 2, 0, 1, 2, 0, 0, 3, 1, 0, 3, 0, 1, 3};
    for (const double x : p) put_double(s, x);
    s += "\nMETADATA\nINFORMATION 0\n\nCELLS 5 14\nOFFSETS vtktypeint64\n";
    for (const int o : {0, 4, 5, 8, 14}) put(s, std::uint64_t(o), 8);
    s += "\nCONNECTIVITY vtktypeint64\n";
    for (const int c : {0, 1, 2, 3, 4, 0, 1, 4, 5, 6, 7, 8, 9, 10}) put(s, std::uint64_t(c), 8);
    s += "\nCELL_TYPES 4\n";
    for (const int t : {9, 1, 5, 13}) put(s, std::uint64_t(t), 4);
    s += "\nCELL_DATA 4\nSCALARS g short\nLOOKUP_TABLE default\n";
    for (const int g : {7, 9, 8, 7}) put(s, std::uint64_t(g), 2);
    s += "\n";
    return s;
}

TEST(VtkLegacy, AsciiAndBinaryVersionsGiveTheSameCells) {
    for (const std::string& file : {ascii42(), binary51()}) {
        const FeCells c = read_vtk_legacy(file, "m.vtk", "g");
        ASSERT_EQ(c.points.size(), 11u);
        EXPECT_EQ(c.points[4], Vec3(0.5, 0.5, 1));
        // Runs of one type are blocks, in file order (element ids 1 + the cell's index).
        ASSERT_EQ(c.blocks.size(), 4u);
        EXPECT_EQ(c.blocks[0].type, "quad");
        EXPECT_EQ(c.blocks[1].type, "vertex");
        EXPECT_EQ(c.blocks[2].type, "triangle");
        EXPECT_EQ(c.blocks[3].type, "wedge");
        EXPECT_EQ(c.blocks[0].nodes, (std::vector<std::int64_t>{0, 1, 2, 3}));
        EXPECT_EQ(c.blocks[2].nodes, (std::vector<std::int64_t>{0, 1, 4}));
        // VTK's wedge 0..5 is meshio's (Gmsh's prism) 0 2 1 3 5 4.
        EXPECT_EQ(c.blocks[3].nodes, (std::vector<std::int64_t>{5, 7, 6, 8, 10, 9}));
        // Groups "g_<value>" in order of first use; the vertex is skipped (no group).
        EXPECT_EQ(c.groups, (std::vector<std::string>{"g_7", "g_8"}));
        EXPECT_EQ(c.blocks[0].group, std::vector<std::int32_t>{0});
        EXPECT_TRUE(c.blocks[1].group.empty());
        EXPECT_EQ(c.blocks[2].group, std::vector<std::int32_t>{1});
        EXPECT_EQ(c.blocks[3].group, std::vector<std::int32_t>{0});
    }
    // Without a field: no groups, one entity.
    const FeCells c = read_vtk_legacy(ascii42(), "m.vtk", "");
    EXPECT_TRUE(c.groups.empty());
    EXPECT_EQ(c.blocks[0].entity, std::vector<std::int64_t>{1});
    EXPECT_EQ(vtk_legacy_version(binary51()), 5);
    EXPECT_EQ(vtk_legacy_version("solid x\n"), -1);
}

TEST(VtkLegacy, MalformedFilesAreRefusedWithTheirLineAndRule) {
    const std::string a = ascii42();
    const auto replaced = [&](const std::string& from, const std::string& to) {
        std::string s = a;
        s.replace(s.find(from), from.size(), to);
        return s;
    };
    EXPECT_EQ(refusal(a), "");
    EXPECT_EQ(refusal(a, "t"), "m.vtk: line 16: the cell array 't' is not of an integer type; --objects-by field:t takes one integer per cell");
    EXPECT_EQ(refusal(a, "h"), "m.vtk: --objects-by field:h: the file has no cell array 'h' (CELL_DATA, SCALARS or FIELD)");
    EXPECT_EQ(refusal("# vtk DataFile Version 4.2\nt\nASCII\nDATASET POLYDATA\n"),
              "m.vtk: line 4: DATASET POLYDATA: ffcube's VTK reader reads UNSTRUCTURED_GRID (without --objects-by field:NAME, Gmsh "
              "reads version 4.2 and older POLYDATA)");
    EXPECT_EQ(refusal(replaced("9 1 5 13", "9 1 7 13")),
              "m.vtk: cell 2 is of VTK type 7, which ffcube does not read (it reads 1 (vertex), 2 (vertex), 3 (line), 4 (line), 21 "
              "(line3), 35 (line4), 5 (triangle), 9 (quad), 22 (triangle6), 23 (quad8), 28 (quad9), 10 (tetra), 12 (hexahedron), 13 "
              "(wedge), 14 (pyramid), 24 (tetra10), 25 (hexahedron20), 29 (hexahedron27), 26 (wedge15), 32 (wedge18), 27 (pyramid13))");
    EXPECT_EQ(refusal(replaced("3 0 1 4", "3 0 1 11")), "m.vtk: cell 2 refers to point 11, which does not exist (the file has 11 points, 0 to 10)");
    EXPECT_EQ(refusal(replaced("9 1 5 13", "9 1 9 13")), "m.vtk: cell 2 (quad, VTK type 9) has 3 nodes; a quad has 4");
    EXPECT_EQ(refusal(replaced("CELLS 4 18", "CELLS 4 19")), "m.vtk: line 12: CELLS: value 18 of 19: 'CELL_TYPES' is not a number");
    EXPECT_EQ(refusal(replaced("POINTS 11", "POINTS 99999999999")),
              "m.vtk: line 5: POINTS 99999999999: more points than the rest of the file holds");
    EXPECT_EQ(refusal(replaced("7 9 8 7", "7 9.5 8 7")), "m.vtk: line 20: FIELD array: value 1 of 4: '9.5' is not an integer");
    EXPECT_EQ(refusal(replaced("CELL_DATA 4", "CELL_DATA 5")), "m.vtk: line 14: CELL_DATA 5: the file has 4 cells before it");
    EXPECT_EQ(refusal(replaced("CELL_DATA", "CELL_STUFF")), "m.vtk: line 14: 'CELL_STUFF' is not a keyword ffcube's VTK reader reads");
    EXPECT_EQ(refusal(a.substr(0, a.find("CELL_TYPES"))), "m.vtk: line 12: the file ends without its POINTS, CELLS and CELL_TYPES");
    // Binary data cut short: named by its byte.
    const std::string b = binary51();
    EXPECT_EQ(refusal(b.substr(0, b.find("CONNECTIVITY") + 40)),
              "m.vtk: byte " + std::to_string(b.find("CONNECTIVITY") + 25) + ": CONNECTIVITY: 14 values are more than the rest of the file holds");
    EXPECT_EQ(refusal("# vtk DataFile Version x\n"), "m.vtk: line 1: not a legacy VTK file (its first line must be '# vtk DataFile Version x.y')");
}

}  // namespace
}  // namespace ffcube
