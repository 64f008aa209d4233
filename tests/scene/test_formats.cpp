// The readers beside OBJ (STL ASCII and binary, View3D .vs3, PLY and glTF through assimp), the
// format dispatcher, --materials and meshing with --no-subdivide. Every file is written here, in
// a temporary directory.
#include <gtest/gtest.h>

#include <limits>

#include <unistd.h>

#include <array>
#include <chrono>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <functional>
#include <string>
#include <vector>

#include "ffcube/core/error.hpp"
#include "ffcube/scene/load_model.hpp"
#include "ffcube/scene/material_map.hpp"
#include "ffcube/scene/mesher.hpp"
#include "ffcube/scene/stl_loader.hpp"
#include "ffcube/scene/vs3_loader.hpp"
#include "support/gltf.hpp"
#include "support/temp_files.hpp"
#include "support/view3d_text.hpp"

namespace ffcube {
namespace {

namespace fs = std::filesystem;

using Temp = test::TempFiles;

std::string read(const fs::path& p) {
    std::ifstream in(p, std::ios::binary);
    return std::string(std::istreambuf_iterator<char>(in), {});
}

const auto error_of = test::input_error_of;

#define EXPECT_CONTAINS(haystack, needle) EXPECT_NE(std::string(haystack).find(needle), std::string::npos) << (haystack)

using Tri = std::array<std::array<float, 3>, 3>;

// Two unit squares, 'a' at z = 0 facing up, 'b' at z = 1 facing down; coordinates exact in float.
const std::vector<Tri> kSquareA = {{{{0, 0, 0}, {1, 0, 0}, {1, 1, 0}}}, {{{0, 0, 0}, {1, 1, 0}, {0, 1, 0}}}};
const std::vector<Tri> kSquareB = {{{{0, 0, 1}, {1, 1, 1}, {1, 0, 1}}}, {{{0, 0, 1}, {0, 1, 1}, {1, 1, 1}}}};

std::array<float, 3> winding_normal(const Tri& t) {
    const float ux = t[1][0] - t[0][0], uy = t[1][1] - t[0][1], uz = t[1][2] - t[0][2];
    const float vx = t[2][0] - t[0][0], vy = t[2][1] - t[0][1], vz = t[2][2] - t[0][2];
    return {uy * vz - uz * vy, uz * vx - ux * vz, ux * vy - uy * vx};
}

std::string ascii_solid(const std::string& name, const std::vector<Tri>& tris) {
    std::string s = "solid " + name + "\n";
    for (const Tri& t : tris) {
        const auto n = winding_normal(t);
        s += "  facet normal " + std::to_string(n[0]) + " " + std::to_string(n[1]) + " " + std::to_string(n[2]) + "\n";
        s += "    outer loop\n";
        for (const auto& v : t) s += "      vertex " + std::to_string(v[0]) + " " + std::to_string(v[1]) + " " + std::to_string(v[2]) + "\n";
        s += "    endloop\n  endfacet\n";
    }
    return s + "endsolid " + name + "\n";
}

std::string binary_stl(const std::vector<Tri>& tris, std::string header = "binary stl written by ffcube's tests") {
    header.resize(80, ' ');
    std::string s = header;
    const auto n = static_cast<std::uint32_t>(tris.size());
    s.append(reinterpret_cast<const char*>(&n), 4);
    for (const Tri& t : tris) {
        const auto normal = winding_normal(t);
        s.append(reinterpret_cast<const char*>(normal.data()), 12);
        for (const auto& v : t) s.append(reinterpret_cast<const char*>(v.data()), 12);
        s.append(2, '\0');
    }
    return s;
}

std::vector<Tri> both_squares() {
    std::vector<Tri> all = kSquareA;
    all.insert(all.end(), kSquareB.begin(), kSquareB.end());
    return all;
}

void expect_same_geometry(const ObjModel& a, const ObjModel& b) {
    ASSERT_EQ(a.positions.size(), b.positions.size());
    for (std::size_t i = 0; i < a.positions.size(); ++i) EXPECT_EQ(a.positions[i], b.positions[i]) << i;
    ASSERT_EQ(a.faces.size(), b.faces.size());
    for (std::size_t i = 0; i < a.faces.size(); ++i) {
        EXPECT_EQ(a.faces[i].v, b.faces[i].v) << i;
        EXPECT_EQ(a.faces[i].material, b.faces[i].material) << i;
    }
}

TEST(Stl, AsciiTwoSolidsAreTwoObjectsWithMergedVertices) {
    Temp t;
    const fs::path p = t.write("two.stl", ascii_solid("a", kSquareA) + ascii_solid("b", kSquareB));
    const ObjModel m = load_model(p);
    EXPECT_EQ(m.objects, (std::vector<std::string>{"a", "b"}));
    ASSERT_EQ(m.faces.size(), 4u);
    EXPECT_EQ(m.positions.size(), 8u);
    EXPECT_EQ(m.merged_vertices, 4u);  // 12 vertex references, 8 distinct points
    EXPECT_EQ(m.faces[0].object, 0u);
    EXPECT_EQ(m.faces[3].object, 1u);
    EXPECT_EQ(m.faces[0].line, 2u);  // the 'facet' line
    EXPECT_EQ(m.materials.size(), 1u);
    EXPECT_EQ(m.materials[0].kd, Vec3(0.5));
    EXPECT_TRUE(m.warnings.empty());
    // Winding kept: 'a' faces +z, 'b' faces -z.
    MeshOptions o;
    o.subdivide = false;
    const Scene s = build_scene(m, o);
    ASSERT_EQ(s.size(), 4u);
    EXPECT_NEAR(s.patches[0].normal.z, 1.0, 1e-15);
    EXPECT_NEAR(s.patches[3].normal.z, -1.0, 1e-15);
    EXPECT_NEAR(s.total_area(), 2.0, 1e-15);
}

TEST(Stl, BinaryGivesTheSameModelAsAscii) {
    Temp t;
    const ObjModel ascii_two = load_model(t.write("two.stl", ascii_solid("a", kSquareA) + ascii_solid("b", kSquareB)));
    const ObjModel binary = load_model(t.write("pair.stl", binary_stl(both_squares())));
    EXPECT_EQ(binary.objects, (std::vector<std::string>{"pair"}));  // a binary file is one object, named by its stem
    expect_same_geometry(ascii_two, binary);
    EXPECT_EQ(binary.merged_vertices, 4u);
    // One ASCII solid named like the stem: the whole model is identical.
    const ObjModel ascii_one = load_model(t.write("one.stl", ascii_solid("pair", both_squares())));
    expect_same_geometry(ascii_one, binary);
    EXPECT_EQ(ascii_one.objects, binary.objects);
}

TEST(Stl, BinaryWhoseHeaderBeginsWithSolid) {
    Temp t;
    const std::string bytes = binary_stl(both_squares(), "solid exported by a CAD program");
    EXPECT_TRUE(is_binary_stl(bytes));
    const ObjModel m = load_model(t.write("cad.stl", bytes));
    EXPECT_EQ(m.faces.size(), 4u);
    EXPECT_EQ(m.objects, (std::vector<std::string>{"cad"}));
}

TEST(Stl, DegenerateFacetsAreDroppedAndCounted) {
    std::vector<Tri> tris = kSquareA;
    tris.push_back({{{0, 0, 0}, {1, 0, 0}, {1, 0, 0}}});  // repeated vertex
    tris.push_back({{{0, 0, 0}, {1, 0, 0}, {2, 0, 0}}});  // collinear: no area
    tris.push_back({{{0, 0, 0}, {0, 0, 0}, {0, 0, 0}}});  // a point
    Temp t;
    for (const std::string& bytes : {binary_stl(tris), ascii_solid("x", tris)}) {
        const ObjModel m = load_model(t.write("d.stl", bytes));
        EXPECT_EQ(m.faces.size(), 2u);
        EXPECT_EQ(m.dropped_degenerate, 3u);
        ASSERT_EQ(m.warnings.size(), 1u);
        EXPECT_CONTAINS(m.warnings[0], "dropped 3 degenerate facets");
    }
    // Only degenerate facets: refused.
    const std::vector<Tri> bad = {tris[2], tris[3]};
    EXPECT_CONTAINS(error_of([&] { load_model(t.write("bad.stl", binary_stl(bad))); }),
                    "bad.stl: no faces with non-zero area (all 2 facets are degenerate)");
}

TEST(Stl, StoredNormalOppositeToTheWindingIsIgnoredWithAWarning) {
    std::string s = ascii_solid("a", kSquareA);
    const std::size_t at = s.find("facet normal ") + 13;
    s.replace(at, s.find('\n', at) - at, "0 0 -1");
    const ObjModel m = parse_stl(s, "n.stl", "n");
    ASSERT_EQ(m.warnings.size(), 1u);
    EXPECT_CONTAINS(m.warnings[0], "1 facets have a stored normal opposite to their vertex order (the first at line 2)");
    MeshOptions o;
    o.subdivide = false;
    EXPECT_GT(build_scene(m, o).patches[0].normal.z, 0.0);  // the winding decides
}

TEST(Stl, TruncatedAndGarbageFilesAreRefusedWithFileAndPlace) {
    Temp t;
    const std::string good = binary_stl(both_squares());
    // Cut inside facet 3 of 4.
    const std::string cut = good.substr(0, 84 + 2 * 50 + 20);
    EXPECT_CONTAINS(error_of([&] { load_model(t.write("cut.stl", cut)); }),
                    "cut.stl: binary STL cut short (or not an STL file): the header says 4 facets (284 bytes), the file has "
                    "204 bytes; facet 3 is incomplete or missing");
    EXPECT_CONTAINS(error_of([&] { load_model(t.write("short.stl", good.substr(0, 40))); }),
                    "short.stl: not an STL file: it does not begin with 'solid' (ASCII) and is 40 bytes");
    std::string garbage(300, '\x7f');
    EXPECT_CONTAINS(error_of([&] { load_model(t.write("garbage.stl", garbage)); }), "garbage.stl: binary STL cut short (or not an STL file)");
    EXPECT_CONTAINS(error_of([&] { load_model(t.write("empty.stl", "")); }), "empty.stl: not an STL file");
    // NaN in a binary facet names the facet.
    std::string nan_file = good;
    const float nan = std::nanf("");
    std::memcpy(nan_file.data() + 84 + 50 + 12 + 4, &nan, 4);
    EXPECT_CONTAINS(error_of([&] { load_model(t.write("nan.stl", nan_file)); }),
                    "nan.stl: facet 2 of 4: vertex 1 has a coordinate that is not a finite number");
    // ASCII cut inside a facet, or before 'endsolid', names the line.
    const std::string ascii = ascii_solid("a", kSquareA);
    EXPECT_CONTAINS(error_of([&] { load_model(t.write("acut.stl", ascii.substr(0, ascii.find("endloop")))); }),
                    "acut.stl:7: the file ends inside the facet begun on line 2 (truncated?)");
    EXPECT_CONTAINS(error_of([&] { load_model(t.write("noend.stl", ascii.substr(0, ascii.find("endsolid")))); }),
                    "noend.stl:16: the file ends inside the solid begun on line 1 (no 'endsolid': truncated?)");
    std::string bad_number = ascii;
    bad_number.replace(bad_number.find("vertex 1.000000"), 15, "vertex nan");
    EXPECT_CONTAINS(error_of([&] { load_model(t.write("anan.stl", bad_number)); }), "anan.stl:5: 'nan' is not a finite number");
    std::string four = ascii;
    four.insert(four.find("    endloop"), "      vertex 0 0 0\n");
    EXPECT_CONTAINS(error_of([&] { load_model(t.write("four.stl", four)); }),
                    "four.stl:7: a facet needs exactly 3 vertices, the one begun on line 2 has more");
    EXPECT_CONTAINS(error_of([&] { load_model(t.write("words.stl", "solid x\nhello\n")); }),
                    "words.stl:2: expected 'facet' or 'endsolid', found 'hello'");
    EXPECT_CONTAINS(error_of([&] { load_model(t.write("ctl.stl", std::string("solid x\n\x01\x02\x03\n", 12))); }),
                    "ctl.stl:2: not an ASCII STL file (control bytes");
}

TEST(Stl, AHundredThousandFacetBinaryFileLoadsQuickly) {
    // A 100 x 500 grid of unit squares, two facets each: 100,000 facets, 50,601 distinct vertices.
    std::vector<Tri> tris;
    tris.reserve(100'000);
    for (int j = 0; j < 100; ++j)
        for (int i = 0; i < 500; ++i) {
            const float x = static_cast<float>(i), y = static_cast<float>(j);
            tris.push_back({{{x, y, 0}, {x + 1, y, 0}, {x + 1, y + 1, 0}}});
            tris.push_back({{{x, y, 0}, {x + 1, y + 1, 0}, {x, y + 1, 0}}});
        }
    Temp t;
    const fs::path p = t.write("big.stl", binary_stl(tris));
    const auto start = std::chrono::steady_clock::now();
    const ObjModel m = load_model(p);
    const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    EXPECT_EQ(m.faces.size(), 100'000u);
    EXPECT_EQ(m.positions.size(), 101u * 501u);
    EXPECT_EQ(m.merged_vertices, 300'000u - 101u * 501u);
    RecordProperty("load_seconds", std::to_string(seconds));
    std::printf("100k-facet binary STL loaded in %.3f s\n", seconds);
    EXPECT_LT(seconds, 5.0);  // a generous bound for a loaded machine (about 0.05 s when idle)
}

// --- View3D ---

const char* kTwoSquaresVs3 = R"(T two parallel unit squares at distance 1 ! exact F = 0.19982
C encl=0 emit=0 eps=1e-6
F 3
V 1 0 0 0
V 2 1 0 0
V 3 1 1 0
V 4 0 1 0
V 5 0 0 1 / a comment after data
V 6 1 0 1
V 7 1 1 1
V 8 0 1 1
S 1 1 2 3 4 0 0 0.9 lower
S 2 5 8 7 6 0 0 0.5 upper
End of data
anything here is not read
)";

TEST(View3d, TwoSquaresAreTwoObjectsWithEmissivityMaterials) {
    const ObjModel m = parse_vs3(kTwoSquaresVs3, "pair.vs3");
    EXPECT_EQ(m.objects, (std::vector<std::string>{"lower", "upper"}));
    ASSERT_EQ(m.faces.size(), 2u);
    EXPECT_EQ(m.faces[0].v, (std::vector<std::uint32_t>{0, 1, 2, 3}));
    EXPECT_EQ(m.faces[1].line, 13u);
    EXPECT_NEAR(m.materials[m.faces[0].material].kd.x, 0.1, 1e-15);  // 1 - 0.9
    EXPECT_NEAR(m.materials[m.faces[1].material].kd.y, 0.5, 1e-15);
    EXPECT_EQ(m.materials[m.faces[1].material].ke, Vec3(0.0));
    // Every control key is honoured: encl, emit, and eps as the accuracy target (--tolerance).
    EXPECT_TRUE(m.warnings.empty());
    EXPECT_EQ(m.view3d.encl, 0);
    EXPECT_EQ(m.view3d.eps, 1e-6);
    EXPECT_EQ(m.view3d.eps_line, 2u);
    EXPECT_TRUE(m.view3d.ignored.empty());
    MeshOptions o;
    o.subdivide = false;
    const Scene s = build_scene(m, o);
    ASSERT_EQ(s.size(), 2u);
    EXPECT_NEAR(s.patches[0].normal.z, 1.0, 1e-15);   // counter-clockwise from the front
    EXPECT_NEAR(s.patches[1].normal.z, -1.0, 1e-15);
}

TEST(View3d, CombinedSurfacesAreOneObjectNamedByTheBase) {
    const ObjModel m = parse_vs3(R"(F 3
V 1 0 0 0
V 2 1 0 0
V 3 1 1 0
V 4 0 1 0
V 5 2 0 0
V 6 2 1 0
S 1 1 2 3 4 0 0 0.9 floor
S 2 2 5 6 3 0 1 0.9 floor_part
S 3 2 5 6 0 0 0 0.9 tri
)",
                                 "c.vs3");
    EXPECT_EQ(m.objects, (std::vector<std::string>{"floor", "tri"}));
    EXPECT_EQ(m.faces[1].object, 0u);
    EXPECT_EQ(m.faces[2].v.size(), 3u);  // v4 = 0: a triangle
    EXPECT_EQ(m.faces[0].material, m.faces[1].material);
}

// O surfaces: numbered with the S surfaces, their objects and faces after every S surface's, each
// as two faces back to back; the mesher keeps them out of the scene's patches (no row, no column)
// and in Scene::drawn.
TEST(View3d, ObstructionSurfacesAreDrawnButHaveNoPatchIndex) {
    const ObjModel m = parse_vs3(std::string(test::kView3dCubeVertices) + R"(S 1 1 2 3 4 0 0 0.9 lower
O 2 5 6 7 8 0 0 0.9 lid
S 3 5 8 7 6 0 0 0.5 upper
)",
                                 "o.vs3");
    EXPECT_EQ(m.objects, (std::vector<std::string>{"lower", "upper", "lid"}));
    EXPECT_EQ(m.obstruction_objects, 1u);
    ASSERT_EQ(m.faces.size(), 4u);
    EXPECT_EQ(m.faces[1].line, 12u);  // upper, before the lid's faces
    EXPECT_EQ(m.faces[2].v, (std::vector<std::uint32_t>{4, 5, 6, 7}));
    EXPECT_EQ(m.faces[3].v, (std::vector<std::uint32_t>{7, 6, 5, 4}));  // the back side
    EXPECT_EQ(m.faces[2].object, 2u);
    EXPECT_EQ(m.faces[3].line, 11u);
    MeshOptions o;
    o.max_patch_edge = 0.5;
    const Scene s = build_scene(m, o);
    ASSERT_EQ(s.size(), 8u);  // lower and upper, 4 patches each
    EXPECT_EQ(s.objects, (std::vector<std::string>{"lower", "upper"}));
    ASSERT_NE(s.drawn, nullptr);
    const Scene& d = *s.drawn;
    ASSERT_EQ(d.size(), 16u);
    EXPECT_EQ(d.obstruction_first, 8u);
    EXPECT_EQ(s.obstruction_first, std::numeric_limits<std::uint32_t>::max());
    for (std::size_t i = 0; i < s.size(); ++i) {
        EXPECT_EQ(s.patch_vertices(i), d.patch_vertices(i)) << i;
        EXPECT_EQ(s.patches[i].object, d.patches[i].object) << i;
    }
    for (std::size_t i = 8; i < 16; ++i) EXPECT_EQ(d.patches[i].object, 2u) << i;
    EXPECT_NEAR(d.patches[8].normal.z, 1.0, 1e-15);
    EXPECT_NEAR(d.patches[12].normal.z, -1.0, 1e-15);
    EXPECT_EQ(s.grids.size(), 2u);
    EXPECT_EQ(d.grids.size(), 4u);
    EXPECT_EQ(s.fingerprint, d.fingerprint);  // the obstructions change every row
    // Without the lid the fingerprint differs.
    ObjModel bare = m;
    bare.faces.resize(2);
    bare.objects.resize(2);
    bare.obstruction_objects = 0;
    EXPECT_NE(build_scene(bare, o).fingerprint, s.fingerprint);
    EXPECT_EQ(build_scene(bare, o).drawn, nullptr);
}

TEST(View3d, RefusalsNameTheLine) {
    const std::string head = "F 3\nV 1 0 0 0\nV 2 1 0 0\nV 3 1 1 0\nV 4 0 1 0\n";
    const auto err = [&](const std::string& tail) { return error_of([&] { parse_vs3(head + tail, "r.vs3"); }); };
    // Obstruction-only surfaces have no row or column: nothing to subtract from, combine with, or
    // radiate.
    EXPECT_CONTAINS(err("S 1 1 2 3 4 0 0 0.9 a\nO 2 1 2 3 4 1 0 0.9 block\n"),
                    "r.vs3:7: obstruction surface 2 has base 1: an O surface cannot be a subsurface");
    EXPECT_CONTAINS(err("S 1 1 2 3 4 0 0 0.9 a\nO 2 1 2 3 4 0 1 0.9 block\n"),
                    "r.vs3:7: obstruction surface 2 has cmb 1: an O surface cannot be combined");
    EXPECT_CONTAINS(err("O 1 1 2 3 4 0 0 0.9 block\nS 2 1 2 3 4 0 1 0.9 a\n"),
                    "r.vs3:7: cmb 1 names an obstruction surface (O)");
    EXPECT_CONTAINS(err("O 1 1 2 3 4 0 0 0.9 block\nN 2 4 3 2 1 1 0 0.9 a\n"),
                    "r.vs3:7: base 1 of a null surface must be a radiating surface (S)");
    EXPECT_CONTAINS(err("O 1 1 2 3 4 0 0 0.9 block\nS 2 1 2 3 0 0 0 0.9 block\n"),
                    "r.vs3:7: surface name 'block' is already used on line 6");
    EXPECT_CONTAINS(err("O 1 1 2 3 4 0 0 0.9 block\n"), "r.vs3: no S surfaces");
    EXPECT_CONTAINS(err("S 1 1 2 3 4 0 0 0.9 a\nO 2 1 2 3 9 0 0 0.9 b\n"), "r.vs3:7: vertex 9 is not defined");
    EXPECT_CONTAINS(err("S 1 1 2 3 9 0 0 0.9 a\n"), "r.vs3:6: vertex 9 is not defined (the file defines 4 vertices)");
    EXPECT_CONTAINS(err("S 1 1 2 3 4 0 0 1.5 a\n"), "r.vs3:6: emissivity 1.5 must be within [0,1]");
    EXPECT_CONTAINS(err("S 1 1 2 3 4 1 0 0.9 a\n"), "r.vs3:6: base 1 must name an earlier surface (this is surface 1)");
    // Subsurfaces and null surfaces lie on their base, inside it, facing as View3D requires.
    EXPECT_CONTAINS(err("S 1 1 2 3 4 0 0 0.9 a\nV 5 0.5 0.5 0.1\nS 2 1 2 5 0 1 0 0.9 b\n"),
                    "r.vs3:8: subsurface 2 cannot lie on its base surface 1 (line 6): a vertex (0.5, 0.5, 0.1) is 0.1 off the "
                    "base's plane");
    EXPECT_CONTAINS(err("S 1 1 2 3 0 0 0 0.9 a\nS 2 1 3 4 0 1 0 0.9 b\n"),
                    "r.vs3:7: subsurface 2 cannot lie on its base surface 1 (line 6): a vertex (0, 1, 0) lies 0.707 outside the "
                    "base");
    EXPECT_CONTAINS(err("S 1 1 2 3 4 0 0 0.9 a\nS 2 3 2 1 0 1 0 0.9 b\n"),
                    "r.vs3:7: subsurface 2 cannot lie on its base surface 1 (line 6): it does not face the way its base faces");
    EXPECT_CONTAINS(err("S 1 1 2 3 4 0 0 0.9 a\nN 2 1 2 3 0 1 0 0.9 b\n"),
                    "r.vs3:7: null surface 2 cannot lie on its base surface 1 (line 6): it does not face its base");
    EXPECT_CONTAINS(err("S 1 1 2 3 4 0 0 0.9 a\nS 2 1 2 3 0 1 0 0.9 b\nN 3 3 2 1 0 1 0 0.9 c\n"),
                    "r.vs3:8: surface 3 overlaps surface 2 (line 7) on their base surface 1 by 0.5");
    EXPECT_CONTAINS(err("S 1 1 2 3 4 0 0 0.9 a\nN 2 3 2 1 0 0 0 0.9 b\n"), "r.vs3:7: null surface 2 has base 0");
    EXPECT_CONTAINS(err("S 1 1 2 3 4 0 0 0.9 a\nN 2 3 2 1 0 1 1 0.9 b\n"), "r.vs3:7: null surface 2 has cmb 1");
    EXPECT_CONTAINS(err("S 1 1 2 3 4 0 0 0.9 a\nN 2 3 2 1 0 1 0 0.9 b\nS 3 1 2 3 0 2 0 0.9 c\n"),
                    "r.vs3:8: base 2 is a null surface (N)");
    EXPECT_CONTAINS(err("S 1 1 2 3 4 0 0 0.9 a\nM 2 3 2 1 0 0 0 0.9 b\n"), "r.vs3:7: masking surface 2 has base 0");
    EXPECT_CONTAINS(err("S 1 1 2 3 4 0 0 0.9 a\nM 2 1 2 3 0 1 0 0.9 b\n"),
                    "r.vs3:7: masking surface 2 cannot lie on its base surface 1 (line 6): it does not face its base");
    EXPECT_CONTAINS(err("S 1 1 2 3 4 0 0 0.9 a\nM 2 3 2 1 0 1 0 0.9 b\nS 3 1 2 3 0 0 2 0.9 c\n"),
                    "r.vs3:8: cmb 2 names a masking surface (M)");
    EXPECT_CONTAINS(err("S 1 1 2 3 4 0 2 0.9 a\n"), "r.vs3:6: cmb 2 must name an earlier surface");
    EXPECT_CONTAINS(err("S 1 1 2 3 4 0 0 0.9\n"), "r.vs3:6: missing the surface name");
    EXPECT_CONTAINS(err("S 2 1 2 3 4 0 0 0.9 a\n"), "r.vs3:6: surface number 2 is out of order (expected 1");
    EXPECT_CONTAINS(err("S 1 1 2 3 4 0 0 0.9 a\nS 2 1 2 3 0 0 0 0.9 a\n"), "r.vs3:7: surface name 'a' is already used on line 6");
    EXPECT_CONTAINS(err("S 1 1 2 2 4 0 0 0.9 a\n"), "r.vs3:6: vertex 2 appears twice in the surface");
    EXPECT_CONTAINS(err("V 6 0 0 0\n"), "r.vs3:6: vertex number 6 is out of order (expected 5");
    EXPECT_CONTAINS(err("V 5 0 inf 0\n"), "r.vs3:6: 'inf' is not a finite number");
    EXPECT_CONTAINS(err("Q 1\n"), "r.vs3:6: unknown element 'Q'");
    EXPECT_CONTAINS(err(""), "r.vs3: no S surfaces");
    EXPECT_CONTAINS(error_of([] { parse_vs3("F 2\n", "f.vs3"); }), "f.vs3:1: geometry format '2' is not supported");
    EXPECT_CONTAINS(error_of([] { parse_vs3(std::string("T x\n\0\0", 6), "b.vs3"); }), "b.vs3:2: not a View3D file");
}

// --- the dispatcher, --materials, --no-subdivide ---

TEST(LoadModel, FormatsByExtensionAndByName) {
    EXPECT_EQ(format_for_path("a.STL"), SceneFormat::Stl);
    EXPECT_EQ(format_for_path("a.vs3"), SceneFormat::View3d);
    EXPECT_EQ(format_for_path("a.obj"), SceneFormat::Obj);
    EXPECT_EQ(format_for_path("a.ply"), SceneFormat::Assimp);
    EXPECT_EQ(format_for_path("a.gltf"), SceneFormat::Assimp);
    EXPECT_EQ(format_for_path("a.glb"), SceneFormat::Assimp);
    EXPECT_EQ(format_for_path("scene"), SceneFormat::Obj);  // as before: no extension is OBJ
    EXPECT_EQ(parse_scene_format("ply"), SceneFormat::Assimp);
    EXPECT_CONTAINS(error_of([] { parse_scene_format("dxf"); }), "--format dxf: unknown format");
    Temp t;
    const fs::path p = t.write("pair.txt", kTwoSquaresVs3);
    EXPECT_EQ(load_model(p, SceneFormat::View3d).faces.size(), 2u);
    EXPECT_CONTAINS(error_of([&] { load_model(t.write("x.stl", "solid")); }), "x.stl:1: the file ends inside the solid");
    EXPECT_CONTAINS(error_of([] { load_model("/nonexistent/x.stl"); }), "/nonexistent/x.stl: cannot read the scene: no such file");
}

TEST(MaterialMap, SetsKdAndKePerObject) {
    ObjModel m = parse_vs3(kTwoSquaresVs3, "pair.vs3");
    apply_material_map(m, "object,kd_r,kd_g,kd_b,ke_r,ke_g,ke_b\n# the lamp\nupper,0.8,0.7,0.6,10,10,10\nghost,0,0,0,0,0,0\n",
                       "m.csv");
    const Material& upper = m.materials[m.faces[1].material];
    EXPECT_EQ(upper.name, "upper");
    EXPECT_EQ(upper.kd, Vec3(0.8, 0.7, 0.6));
    EXPECT_EQ(upper.ke, Vec3(10.0));
    EXPECT_NEAR(m.materials[m.faces[0].material].kd.x, 0.1, 1e-15);  // not named: unchanged
    EXPECT_CONTAINS(m.warnings.back(), "m.csv:4: the scene has no object 'ghost'");
    EXPECT_CONTAINS(error_of([&] { apply_material_map(m, "upper,1.5,0,0,0,0,0\n", "m.csv"); }), "m.csv:1: Kd 1.5 must be within [0,1)");
    EXPECT_CONTAINS(error_of([&] { apply_material_map(m, "upper,0,0,0,-1,0,0\n", "m.csv"); }), "m.csv:1: Ke -1 must be >= 0");
    EXPECT_CONTAINS(error_of([&] { apply_material_map(m, "upper,0,0\n", "m.csv"); }), "m.csv:1: 3 fields; each line is object,kd_r,kd_g,kd_b,ke_r,ke_g,ke_b (7 fields)");
}

TEST(MaterialMap, AnEmptyTripleKeepsTheFilesKdOrKe) {
    ObjModel m = parse_vs3(kTwoSquaresVs3, "pair.vs3");
    // Two faces of "upper" with different materials: each keeps its own Kd and takes the new Ke.
    m.faces.push_back(m.faces[1]);
    m.materials.push_back(Material{"blue", Vec3(0.1, 0.2, 0.9), Vec3(7.0)});
    m.faces.back().material = static_cast<std::uint32_t>(m.materials.size() - 1);
    const Vec3 kd1 = m.materials[m.faces[1].material].kd, ke0 = m.materials[m.faces[0].material].ke;
    const Vec3 kd0 = m.materials[m.faces[0].material].kd;
    apply_material_map(m, "object,kd_r,kd_g,kd_b,ke_r,ke_g,ke_b\nupper,,,,3,4,5\nlower,0.25,0.5,0.75,,,\n", "m.csv");
    EXPECT_EQ(m.materials[m.faces[1].material].kd, kd1);
    EXPECT_EQ(m.materials[m.faces[1].material].ke, Vec3(3, 4, 5));
    EXPECT_EQ(m.materials[m.faces[2].material].kd, Vec3(0.1, 0.2, 0.9));
    EXPECT_EQ(m.materials[m.faces[2].material].ke, Vec3(3, 4, 5));
    EXPECT_EQ(m.materials[m.faces[0].material].kd, Vec3(0.25, 0.5, 0.75));
    EXPECT_EQ(m.materials[m.faces[0].material].ke, ke0);
    EXPECT_NE(kd0, Vec3(0.25, 0.5, 0.75));  // so that the line above shows a change
    // Both empty: the object keeps its materials.
    const std::uint32_t before = m.faces[0].material;
    apply_material_map(m, "lower,,,,,,\n", "m.csv");
    EXPECT_EQ(m.faces[0].material, before);
}

TEST(MaterialMap, RefusalsNameTheFileLineAndRule) {
    ObjModel m = parse_vs3(kTwoSquaresVs3, "pair.vs3");
    const std::vector<Material> materials = m.materials;
    const auto refused = [&](const char* csv) {
        ObjModel copy = m;
        return error_of([&] { apply_material_map(copy, csv, "m.csv"); });
    };
    EXPECT_CONTAINS(refused("# c\nupper,0.5,,,1,1,1\n"), "m.csv:2: Kd has 2 of its 3 fields empty: give all three, or leave all three empty");
    EXPECT_CONTAINS(refused("upper,0.5,0.5,0.5,1,,1\n"), "m.csv:1: Ke has 1 of its 3 fields empty");
    EXPECT_CONTAINS(refused("upper,,,,x,1,1\n"), "m.csv:1: ");
    EXPECT_CONTAINS(refused("upper,,,,x,1,1\n"), "Ke: emitted radiosity >= 0");
    EXPECT_CONTAINS(refused("upper,0.5,0.5,abc,,,\n"), "Kd: diffuse reflectance within [0,1]");
    EXPECT_CONTAINS(refused("upper,,,,1,-2,1\n"), "m.csv:1: Ke -2 must be >= 0");
    EXPECT_CONTAINS(refused("upper,0.5,1.25,0.5,,,\n"), "m.csv:1: Kd 1.25 must be within [0,1)");
    EXPECT_CONTAINS(refused("upper,,,,1,1,1\nupper,0.5,0.5,0.5,,,\n"), "m.csv:2: object 'upper' is given twice (first on line 1)");
    EXPECT_CONTAINS(refused(",,,,1,1,1\n"), "m.csv:1: the object name is empty");
    // Nothing half-applied: a refusal on line 2 leaves line 1's object as it was.
    ObjModel copy = m;
    EXPECT_CONTAINS(error_of([&] { apply_material_map(copy, "upper,,,,1,1,1\nlower,0.5,,,,,\n", "m.csv"); }), "m.csv:2: Kd has 2");
    EXPECT_EQ(copy.materials.size(), materials.size());
    EXPECT_EQ(copy.faces[1].material, m.faces[1].material);
}

TEST(NoSubdivide, EveryFaceIsOnePatchOrTheFaceIsRefused) {
    const ObjModel m = parse_vs3(kTwoSquaresVs3, "pair.vs3");
    MeshOptions o;
    o.subdivide = false;
    const Scene s = build_scene(m, o);
    EXPECT_EQ(s.size(), 2u);
    EXPECT_EQ(s.patches[0].count, 4u);
    EXPECT_EQ(s.stats.how, "--no-subdivide (2 patches)");
    // A large triangle stays one patch too.
    Temp t;
    const ObjModel big = load_model(t.write("big.stl", binary_stl({{{{0, 0, 0}, {1000, 0, 0}, {0, 1000, 0}}}})));
    EXPECT_EQ(build_scene(big, o).size(), 1u);
    // A pentagon cannot be one patch (a patch is a triangle or a convex quad).
    const ObjModel pentagon = load_model(t.write("p.obj", "v 0 0 0\nv 1 0 0\nv 1.5 1 0\nv 0.5 1.7 0\nv -0.5 1 0\nf 1 2 3 4 5\n"));
    EXPECT_CONTAINS(error_of([&] { build_scene(pentagon, o); }), "p.obj:6: --no-subdivide: this face of 5 vertices is not a triangle");
}

// --- assimp: PLY and glTF ---

TEST(Assimp, AsciiPlyKeepsQuads) {
    Temp t;
    const fs::path p = t.write("q.ply", R"(ply
format ascii 1.0
comment a unit square and a triangle beside it
element vertex 5
property float x
property float y
property float z
element face 2
property list uchar int vertex_indices
end_header
0 0 0
1 0 0
1 1 0
0 1 0
2 0 0
4 0 1 2 3
3 1 4 2
)");
    const ObjModel m = load_model(p);
    ASSERT_EQ(m.faces.size(), 2u);
    EXPECT_EQ(m.faces[0].v.size(), 4u);  // not triangulated
    EXPECT_EQ(m.faces[1].v.size(), 3u);
    EXPECT_EQ(m.materials.size(), 1u);
    MeshOptions o;
    o.subdivide = false;
    const Scene s = build_scene(m, o);
    ASSERT_EQ(s.size(), 2u);
    EXPECT_NEAR(s.patches[0].area, 1.0, 1e-12);
    EXPECT_NEAR(s.patches[1].area, 0.5, 1e-12);
    EXPECT_NEAR(s.patches[0].normal.z, 1.0, 1e-12);
    // A header cut short (assimp 5.2.5 would loop forever on it) and a body cut short.
    EXPECT_CONTAINS(error_of([&] { load_model(t.write("bad.ply", "ply\nformat ascii 1.0\nelement vertex 2\n")); }),
                    "bad.ply: PLY header without 'end_header'");
    const std::string text = read(p);
    EXPECT_CONTAINS(error_of([&] { load_model(t.write("cut.ply", text.substr(0, text.find("4 0 1")))); }),
                    "cut.ply:8: element 'face' declares 2 records, the file ends after 0");
}

using test::base64;  // support/gltf.hpp

TEST(Assimp, GltfWithAnEmbeddedBufferAndANodeTransform) {
    // A unit square as two triangles, scaled by 2 in x by its node: area 2, object "roof".
    const float pos[12] = {0, 0, 0, 1, 0, 0, 1, 1, 0, 0, 1, 0};
    const std::uint16_t idx[6] = {0, 1, 2, 0, 2, 3};
    std::string buffer(reinterpret_cast<const char*>(pos), 48);
    buffer.append(reinterpret_cast<const char*>(idx), 12);
    const std::string gltf = R"({"asset":{"version":"2.0"},"scene":0,"scenes":[{"nodes":[0]}],
 "nodes":[{"name":"roof","mesh":0,"scale":[2,1,1]}],
 "meshes":[{"name":"square","primitives":[{"attributes":{"POSITION":0},"indices":1}]}],
 "buffers":[{"byteLength":60,"uri":"data:application/octet-stream;base64,)" +
                             base64(buffer) + R"("}],
 "bufferViews":[{"buffer":0,"byteOffset":0,"byteLength":48},{"buffer":0,"byteOffset":48,"byteLength":12}],
 "accessors":[{"bufferView":0,"componentType":5126,"count":4,"type":"VEC3","min":[0,0,0],"max":[1,1,0]},
              {"bufferView":1,"componentType":5123,"count":6,"type":"SCALAR"}]})";
    Temp t;
    const ObjModel m = load_model(t.write("roof.gltf", gltf));
    EXPECT_EQ(m.objects, (std::vector<std::string>{"roof"}));
    ASSERT_EQ(m.faces.size(), 2u);
    MeshOptions o;
    o.subdivide = false;
    const Scene s = build_scene(m, o);
    EXPECT_NEAR(s.total_area(), 2.0, 1e-12);
    EXPECT_NEAR(s.patches[0].normal.z, 1.0, 1e-12);
}

}  // namespace
}  // namespace ffcube
