// Materials read through assimp, solved by the real binary (docs/scene-format.md, "Materials
// through assimp"): closed enclosures ("furnaces") whose radiosity has a closed form, built from
// glTF and PLY files written here.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>
#include <vector>

#include "cli/cli_util.hpp"
#include "support/gltf.hpp"

namespace ffcube {
namespace {

using test::read_text;
using test::run_ffcube;
using test::TempDir;
using test::write_file;

struct PatchB {
    std::string object;
    double area = 0;
    Vec3 B{0.0};
};

// --radiosity CSV: patch,object,area,B_r,B_g,B_b.
std::vector<PatchB> read_radiosity(const std::string& text) {
    std::vector<PatchB> out;
    std::istringstream in(text);
    std::string line;
    std::getline(in, line);
    while (std::getline(in, line)) {
        std::vector<std::string> f;
        std::istringstream fields(line);
        for (std::string x; std::getline(fields, x, ',');) f.push_back(x);
        out.push_back({f.at(1), std::stod(f.at(2)), Vec3(std::stod(f.at(3)), std::stod(f.at(4)), std::stod(f.at(5)))});
    }
    return out;
}

// The direct solver solves B = E + ρFB to rounding, so what is left is F: the closed cube's
// 12 triangles are all near and mutually unoccluded, so every entry is the exact analytic value
// stored in float32 (2^-24 relative); a row of 10 nonzero entries sums to 1 within 10 × 6e-8
// = 6e-7, and B = E/(1 − ρ Σ_j F_ij) moves by ρ E/(1 − ρ)² × 6e-7: at ρ = 0.8, 20 × 6e-7 = 1.2e-5
// of E. 2e-5 × B bounds that (B ≥ E).
constexpr double kRelative = 2e-5;
const char* kSolve = " --no-subdivide --solver direct -q --radiosity ";

TEST(AssimpMaterialsCli, GltfFurnaceWithALampFloorConservesEnergy) {
    // One object with two materials (two primitives): the floor emits, the other five faces do not;
    // all reflect ρ = (0.8, 0.5, 0.2). Closed and reciprocal, every watt emitted is reflected
    // until absorbed: Σ A_i B_i = Σ A_i E_i / (1 − ρ), so the area-weighted mean B over the six
    // unit faces is (E/6)/(1 − ρ) = (5/6, 1/3, 5/24) for E = 1.
    std::vector<test::GltfPrimitive> faces = test::unit_cube_inward();
    faces[0].material = 0;
    for (std::size_t k = 1; k < faces.size(); ++k) faces[k].material = 1;
    const std::string materials = R"([
      {"name":"lamp","pbrMetallicRoughness":{"baseColorFactor":[0.8,0.5,0.2,1]},"emissiveFactor":[1,1,1]},
      {"name":"wall","pbrMetallicRoughness":{"baseColorFactor":[0.8,0.5,0.2,1]}}])";
    TempDir dir;
    write_file(dir / "furnace.gltf", test::gltf_json({{"box", faces}}, materials));
    const auto r = run_ffcube("solve " + (dir / "furnace.gltf") + kSolve + (dir / "b.csv") + " --report " + (dir / "r.json"));
    ASSERT_EQ(r.code, 0) << r.output;
    const std::vector<PatchB> patches = read_radiosity(read_text(dir / "b.csv"));
    ASSERT_EQ(patches.size(), 12u);
    Vec3 sum(0.0);
    double area = 0.0;
    for (const PatchB& p : patches) sum += p.area * p.B, area += p.area;
    const Vec3 mean = sum / area, want(5.0 / 6.0, 1.0 / 3.0, 5.0 / 24.0);
    for (int c = 0; c < 3; ++c) EXPECT_NEAR(mean[c], want[c], kRelative * want[c]) << "channel " << c;
    // Had every face taken the lamp (materials per object instead of per face), the mean would be
    // E/(1 − ρ) = (5, 2, 1.25); had none, 0.
    const auto report = nlohmann::json::parse(read_text(dir / "r.json"));
    EXPECT_EQ(report["loading"]["materials"]["from_file"].get<int>(), 2);
    EXPECT_EQ(report["loading"]["materials"]["faces_material"].get<int>(), 12);
    EXPECT_EQ(report["loading"]["materials"]["faces_default"].get<int>(), 0);
}

TEST(AssimpMaterialsCli, GltfVertexColouredFurnaceIsEOverOneMinusRho) {
    // Every face emits E = emissiveFactor and reflects ρ = COLOR_0 × baseColorFactor: a uniform
    // closed enclosure, so every patch has B = E/(1 − ρ) (rows summing to 1 are all it needs).
    std::vector<test::GltfPrimitive> faces = test::unit_cube_inward();
    for (test::GltfPrimitive& f : faces) {
        f.material = 0;
        f.colors.assign(4, Vec3(0.8, 1.0, 0.4));
    }
    TempDir dir;
    write_file(dir / "v.gltf",
          test::gltf_json({{"box", faces}},
                          R"([{"name":"glow","pbrMetallicRoughness":{"baseColorFactor":[1,0.5,0.5,1]},"emissiveFactor":[0.5,0.25,1]}])"));
    const auto r = run_ffcube("solve " + (dir / "v.gltf") + kSolve + (dir / "b.csv"));
    ASSERT_EQ(r.code, 0) << r.output;
    const Vec3 want(0.5 / 0.2, 0.25 / 0.5, 1.0 / 0.8);  // ρ = (0.8, 0.5, 0.2)
    const std::vector<PatchB> patches = read_radiosity(read_text(dir / "b.csv"));
    ASSERT_EQ(patches.size(), 12u);
    for (const PatchB& p : patches)
        for (int c = 0; c < 3; ++c) EXPECT_NEAR(p.B[c], want[c], kRelative * want[c]) << "channel " << c;
}

// Vertex k of the unit cube (the order of test::unit_cube_inward) with a colour, as a PLY line.
std::string fmt_vertex(int k) {
    const int x = (k == 1 || k == 2 || k == 5 || k == 6), y = (k == 2 || k == 3 || k == 6 || k == 7), z = k >= 4;
    return std::to_string(x) + " " + std::to_string(y) + " " + std::to_string(z) + " 204 102 51\n";
}

// The closed unit cube as one PLY object with vertex colours (204, 102, 51): Kd = (0.8, 0.4, 0.2),
// no emission (PLY has none).
std::string coloured_cube_ply() {
    std::string ply = "ply\nformat ascii 1.0\nelement vertex 8\nproperty float x\nproperty float y\nproperty float z\n"
                      "property uchar red\nproperty uchar green\nproperty uchar blue\nelement face 6\n"
                      "property list uchar int vertex_indices\nend_header\n";
    for (int k = 0; k < 8; ++k) ply += fmt_vertex(k);
    return ply + "4 0 1 2 3\n4 4 7 6 5\n4 0 4 5 1\n4 3 2 6 7\n4 0 3 7 4\n4 1 5 6 2\n";
}

// The name of the object of the first patch, as `formfactors --patch-table` gives it.
std::string first_object(const std::string& table) {
    const std::size_t line = table.find('\n') + 1, a = table.find(',', line) + 1;
    return table.substr(a, table.find(',', a) - a);
}

TEST(AssimpMaterialsCli, PlyColoursAreReportedAndMaterialsCsvOverridesThem) {
    // --materials giving the object ρ = 0.5 and E = 1: B = E/(1 − ρ) = 2 on every patch.
    TempDir dir;
    write_file(dir / "cube.ply", coloured_cube_ply());
    auto r = run_ffcube("formfactors " + (dir / "cube.ply") + " --no-subdivide -q --patch-table " + (dir / "t.csv") +
                        " --report " + (dir / "r.json"));
    ASSERT_EQ(r.code, 0) << r.output;
    const auto report = nlohmann::json::parse(read_text(dir / "r.json"));
    EXPECT_EQ(report["loading"]["materials"]["faces_vertex_colour"].get<int>(), 6);
    EXPECT_EQ(report["loading"]["materials"]["from_file"].get<int>(), 0);
    write_file(dir / "m.csv", first_object(read_text(dir / "t.csv")) + ",0.5,0.5,0.5,1,1,1\n");
    r = run_ffcube("solve " + (dir / "cube.ply") + " --materials " + (dir / "m.csv") + kSolve + (dir / "b.csv"));
    ASSERT_EQ(r.code, 0) << r.output;
    const std::vector<PatchB> patches = read_radiosity(read_text(dir / "b.csv"));
    ASSERT_EQ(patches.size(), 6u);
    // ρ = 0.5: the bound above at ρ = 0.5 is 0.5 × 1/(0.25) × 6e-7 = 1.2e-6 of E, under 2e-5 × 2.
    for (const PatchB& p : patches)
        for (int c = 0; c < 3; ++c) EXPECT_NEAR(p.B[c], 2.0, kRelative * 2.0) << p.object;
}

TEST(AssimpMaterialsCli, MaterialsCsvWithOnlyKeLightsAPlyKeepingItsColours) {
    // "object,,,,1,1,1": E = 1 on every face, Kd the PLY's own ρ = (0.8, 0.4, 0.2): a uniform closed
    // enclosure, B = E/(1 − ρ) = (5, 5/3, 1.25). Had the CSV replaced Kd by the default 0.5, B = 2.
    // The colours are float32 c/255 (2^-24 relative: ΔB/B = ρ/(1 − ρ) × 6e-8 ≤ 2.4e-7), well under kRelative.
    TempDir dir;
    write_file(dir / "cube.ply", coloured_cube_ply());
    auto r = run_ffcube("formfactors " + (dir / "cube.ply") + " --no-subdivide -q --method raycast --rays 1 --patch-table " +
                        (dir / "t.csv"));
    ASSERT_EQ(r.code, 0) << r.output;
    write_file(dir / "m.csv", "object,kd_r,kd_g,kd_b,ke_r,ke_g,ke_b\n" + first_object(read_text(dir / "t.csv")) + ",,,,1,1,1\n");
    r = run_ffcube("solve " + (dir / "cube.ply") + " --materials " + (dir / "m.csv") + kSolve + (dir / "b.csv"));
    ASSERT_EQ(r.code, 0) << r.output;
    const std::vector<PatchB> patches = read_radiosity(read_text(dir / "b.csv"));
    ASSERT_EQ(patches.size(), 6u);
    const Vec3 want(5.0, 5.0 / 3.0, 1.25);
    for (const PatchB& p : patches)
        for (int c = 0; c < 3; ++c) EXPECT_NEAR(p.B[c], want[c], kRelative * want[c]) << p.object << " channel " << c;
    // One of a triple left empty: refused, naming the file, the line and the rule; nothing written.
    write_file(dir / "bad.csv", "# lamp\n" + first_object(read_text(dir / "t.csv")) + ",0.5,,,1,1,1\n");
    r = run_ffcube("solve " + (dir / "cube.ply") + " --materials " + (dir / "bad.csv") + kSolve + (dir / "bad_b.csv"));
    EXPECT_EQ(r.code, 2) << r.output;
    EXPECT_NE(r.output.find((dir / "bad.csv") + ":2: Kd has 2 of its 3 fields empty"), std::string::npos) << r.output;
    EXPECT_FALSE(std::filesystem::exists(dir / "bad_b.csv"));
}

}  // namespace
}  // namespace ffcube
