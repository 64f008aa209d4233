// View3D text shared by the tests: pieces of .vs3 input (each after a T line of the test's own,
// and followed by its own further vertices and surfaces, so line numbers after them are its own)
// and a reader of View3D's output text, written from its readvf.c, not from ffcube's writer.
#pragma once

#include <gtest/gtest.h>

#include <cstddef>
#include <sstream>
#include <string>
#include <vector>

namespace ffcube::test {

// The unit cube's 8 corners, after View3D's format line; the open box's five faces as View3D
// surfaces facing inward (the lid, on 5 6 7 8, is left to each test).
inline constexpr const char* kView3dCubeVertices = R"(F 3
V 1 0 0 0
V 2 1 0 0
V 3 1 1 0
V 4 0 1 0
V 5 0 0 1
V 6 1 0 1
V 7 1 1 1
V 8 0 1 1
)";
inline constexpr const char* kView3dOpenBoxSurfaces = R"(S 1 1 2 3 4 0 0 0.9 floor
S 2 1 5 6 2 0 0 0.9 south
S 3 4 3 7 8 0 0 0.9 north
S 4 1 4 8 5 0 0 0.9 west
S 5 2 6 7 3 0 0 0.9 east
)";

// A View3D text file (--view3d) as View3D's readvf.c reads it: the header's words, then
// whitespace-separated numbers (areas, the n × n factors, emissivities), and nothing after.
struct View3dText {
    std::string program, version;
    int format = -1, encl = -1, emit = -1;
    std::size_t n = 0;
    std::vector<double> area, emissivity;
    std::vector<std::vector<double>> F;
};
inline View3dText read_view3d(const std::string& bytes) {
    View3dText f;
    std::istringstream in(bytes);
    in >> f.program >> f.version >> f.format >> f.encl >> f.emit >> f.n;
    EXPECT_EQ(f.program, "View3D");
    f.area.resize(f.n);
    f.emissivity.resize(f.n);
    f.F.assign(f.n, std::vector<double>(f.n));
    for (auto& a : f.area) in >> a;
    for (auto& row : f.F)
        for (auto& v : row) in >> v;
    for (auto& e : f.emissivity) in >> e;
    EXPECT_TRUE(in) << "short file";
    std::string rest;
    in >> rest;
    EXPECT_TRUE(rest.empty()) << "trailing data: " << rest;
    return f;
}

// The format line and the corners of a 2 × 2 wall in z = 0 (vertices 1–4) and of a 1 × 1
// window in its middle (vertices 5–8): the subsurface tests' wall.
inline constexpr const char* kVs3WindowWallVertices = R"(F 3
V 1 0 0 0
V 2 2 0 0
V 3 2 2 0
V 4 0 2 0
V 5 0.5 0.5 0
V 6 1.5 0.5 0
V 7 1.5 1.5 0
V 8 0.5 1.5 0
)";

}  // namespace ffcube::test
