// Materials of files read through assimp (docs/scene-format.md, "Materials through assimp"):
// glTF baseColorFactor/emissiveFactor per primitive, vertex colours, PLY material elements and
// vertex colours, assimp's default materials, textures, --materials over them, and refusals.
// Every file is written here, in a temporary directory.
#include <gtest/gtest.h>

#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <functional>
#include <string>

#include "ffcube/core/error.hpp"
#include "ffcube/scene/load_model.hpp"
#include "ffcube/scene/material_map.hpp"
#include "support/gltf.hpp"
#include "support/temp_files.hpp"

namespace ffcube {
namespace {

namespace fs = std::filesystem;

using Temp = test::TempFiles;

const auto error_of = test::input_error_of;

#define EXPECT_CONTAINS(haystack, needle) EXPECT_NE(std::string(haystack).find(needle), std::string::npos) << (haystack)

const Material& material_of(const ObjModel& m, std::size_t face) { return m.materials.at(m.faces.at(face).material); }

// Float32 colours in the glTF buffer: exact for these values (0.8 is not, to 2^-24 relative).
constexpr double kFloat = 1e-7;

void expect_vec(const Vec3& got, const Vec3& want, double tol) {
    for (int c = 0; c < 3; ++c) EXPECT_NEAR(got[c], want[c], tol) << "channel " << c;
}

TEST(AssimpMaterials, GltfBaseColorAndEmissivePerPrimitive) {
    // One node, three primitives: a lamp material, a textured one, and none (glTF's default).
    const Vec3 a(0, 0, 0), b(1, 0, 0), c(1, 1, 0), d(0, 1, 0);
    test::GltfNode node{"box", {test::gltf_quad(a, b, c, d, 0), test::gltf_quad(a, b, c, d, 1), test::gltf_quad(a, b, c, d)}};
    const std::string materials = R"([
      {"name":"lamp","pbrMetallicRoughness":{"baseColorFactor":[0.8,0.5,0.25,1]},"emissiveFactor":[1,0.5,0.125]},
      {"name":"painted","pbrMetallicRoughness":{"baseColorFactor":[0.25,0.25,0.25,1],"baseColorTexture":{"index":0}}}],
      "textures":[{"source":0}],"images":[{"uri":"paint.png"}])";
    Temp t;
    ImportedMaterials counts;
    const ObjModel m = load_model(t.write("box.gltf", test::gltf_json({node}, materials)), SceneFormat::Auto, {}, &counts);
    ASSERT_EQ(m.faces.size(), 6u);
    EXPECT_EQ(m.objects, (std::vector<std::string>{"box"}));  // per-face materials, one object
    for (std::size_t f : {0u, 1u}) {
        expect_vec(material_of(m, f).kd, Vec3(0.8, 0.5, 0.25), kFloat);
        expect_vec(material_of(m, f).ke, Vec3(1, 0.5, 0.125), kFloat);
        EXPECT_EQ(material_of(m, f).name, "lamp");
    }
    for (std::size_t f : {2u, 3u}) {  // the texture is ignored, its factor kept
        expect_vec(material_of(m, f).kd, Vec3(0.25), kFloat);
        expect_vec(material_of(m, f).ke, Vec3(0.0), 0.0);
    }
    // No material: OBJ's default (Kd 0.5, Ke 0), not glTF's (baseColor 1: a perfect reflector).
    for (std::size_t f : {4u, 5u}) EXPECT_EQ(m.faces[f].material, 0u);
    expect_vec(m.materials[0].kd, Vec3(0.5), 0.0);
    EXPECT_TRUE(counts.present);
    EXPECT_EQ(counts.from_file, 2u);
    EXPECT_EQ(counts.faces_material, 4u);
    EXPECT_EQ(counts.faces_default, 2u);
    EXPECT_EQ(counts.faces_vertex_colour, 0u);
    EXPECT_EQ(counts.textured, 1u);
    ASSERT_FALSE(m.warnings.empty());
    EXPECT_CONTAINS(m.warnings.back(), "box.gltf: 1 material with colour textures (first 'painted'): textures are ignored");

    // --materials still wins, by object name.
    ObjModel over = m;
    apply_material_map(over, "box,0.1,0.2,0.3,4,5,6\n", "m.csv");
    for (std::size_t f = 0; f < 6; ++f) {
        expect_vec(material_of(over, f).kd, Vec3(0.1, 0.2, 0.3), 0.0);
        expect_vec(material_of(over, f).ke, Vec3(4, 5, 6), 0.0);
    }
}

TEST(AssimpMaterials, GltfVertexColoursMultiplyTheBaseColour) {
    test::GltfPrimitive p = test::gltf_quad({0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}, 0);
    // Per face, the mean of its three vertices' colours, times baseColorFactor (glTF's rule).
    p.colors = {{1, 0.5, 0}, {0.5, 0.5, 0}, {0, 0.5, 0.75}, {0.25, 0.25, 0.25}};
    Temp t;
    ImportedMaterials counts;
    const ObjModel m = load_model(
        t.write("v.gltf", test::gltf_json({{"plate", {p}}}, R"([{"name":"m","pbrMetallicRoughness":{"baseColorFactor":[0.5,1,1,1]},"emissiveFactor":[0,0,1]}])")),
        SceneFormat::Auto, {}, &counts);
    ASSERT_EQ(m.faces.size(), 2u);
    // Face (0,1,2): mean (0.5, 0.5, 0.25) × base (0.5, 1, 1); face (0,2,3): mean (0.41667, 0.41667, 0.33333) × base.
    expect_vec(material_of(m, 0).kd, Vec3(0.25, 0.5, 0.25), kFloat);
    expect_vec(material_of(m, 1).kd, Vec3(0.5 * 1.25 / 3, 1.25 / 3, 1.0 / 3), kFloat);
    expect_vec(material_of(m, 0).ke, Vec3(0, 0, 1), 0.0);
    EXPECT_EQ(counts.faces_vertex_colour, 2u);
    EXPECT_EQ(counts.faces_material, 0u);
}

const char* kPlyHeader = R"(ply
format ascii 1.0
element vertex 4
property float x
property float y
property float z
)";

TEST(AssimpMaterials, PlyVertexColoursAreKdAndAPlyWithoutThemIsDefault) {
    Temp t;
    ImportedMaterials counts;
    // uchar colours: assimp divides by 255.
    const ObjModel m = load_model(t.write("c.ply", std::string(kPlyHeader) + R"(property uchar red
property uchar green
property uchar blue
element face 1
property list uchar int vertex_indices
end_header
0 0 0 204 102 51
1 0 0 204 102 51
1 1 0 102 102 51
0 1 0 102 102 51
4 0 1 2 3
)"),
                                  SceneFormat::Auto, {}, &counts);
    ASSERT_EQ(m.faces.size(), 1u);
    expect_vec(material_of(m, 0).kd, Vec3(153.0 / 255, 0.4, 0.2), kFloat);
    expect_vec(material_of(m, 0).ke, Vec3(0.0), 0.0);
    EXPECT_EQ(counts.from_file, 0u);  // the PLY importer's own material (diffuse 1) is not the file's
    EXPECT_EQ(counts.faces_vertex_colour, 1u);

    // No colours, no material element: OBJ's default, not the importer's white.
    const ObjModel plain = load_model(t.write("p.ply", std::string(kPlyHeader) + R"(element face 1
property list uchar int vertex_indices
end_header
0 0 0
1 0 0
1 1 0
0 1 0
4 0 1 2 3
)"),
                                      SceneFormat::Auto, {}, &counts);
    EXPECT_EQ(plain.faces[0].material, 0u);
    expect_vec(material_of(plain, 0).kd, Vec3(0.5), 0.0);
    EXPECT_EQ(counts.faces_default, 1u);
}

TEST(AssimpMaterials, PlyMaterialElementGivesKdAndPerFaceIndicesAreReported) {
    Temp t;
    ImportedMaterials counts;
    const ObjModel m = load_model(t.write("m.ply", std::string(kPlyHeader) + R"(element face 2
property list uchar int vertex_indices
property int material_index
element material 2
property uchar diffuse_red
property uchar diffuse_green
property uchar diffuse_blue
end_header
0 0 0
1 0 0
1 1 0
0 1 0
3 0 1 2 0
3 0 2 3 1
204 102 51
51 51 51
)"),
                                  SceneFormat::Auto, {}, &counts);
    ASSERT_EQ(m.faces.size(), 2u);
    EXPECT_EQ(counts.from_file, 2u);
    expect_vec(material_of(m, 0).kd, Vec3(0.8, 0.4, 0.2), kFloat);
    // assimp 5.2.5 drops material_index: said, not hidden.
    bool said = false;
    for (const std::string& w : m.warnings) said = said || w.find("per-face material_index is not applied") != std::string::npos;
    EXPECT_TRUE(said);
}

TEST(AssimpMaterials, ColoursOutOfRangeAreRefusedNamingTheMaterial) {
    const test::GltfPrimitive p = test::gltf_quad({0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}, 0);
    Temp t;
    EXPECT_CONTAINS(error_of([&] {
                        load_model(t.write("k.gltf", test::gltf_json({{"x", {p}}}, R"([{"name":"shiny","pbrMetallicRoughness":{"baseColorFactor":[1.5,0.5,0.5,1]}}])")));
                    }),
                    "k.gltf: material 'shiny' (number 1 of the file): diffuse colour (Kd) 1.5 0.5 0.5: each channel must be within [0,1]");
    test::GltfPrimitive q = p;
    q.material = -1;
    q.colors = {{0, 0, 0}, {0, 2, 0}, {0, 0, 0}, {0, 0, 0}};
    EXPECT_CONTAINS(error_of([&] { load_model(t.write("v.gltf", test::gltf_json({{"x", {q}}}, ""))); }), "v.gltf: mesh ");
    EXPECT_CONTAINS(error_of([&] { load_model(t.write("v.gltf", test::gltf_json({{"x", {q}}}, ""))); }),
                    "vertex colour 0 2 0: each channel must be within [0,1]");
}

}  // namespace
}  // namespace ffcube
