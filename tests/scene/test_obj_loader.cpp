// OBJ/MTL input: every bad input of issue 2 is refused with file, line and rule; the unusual but
// valid ones load with exactly the geometry they describe.
#include <gtest/gtest.h>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <functional>
#include <string>
#include <unistd.h>

#include "ffcube/core/error.hpp"
#include "ffcube/scene/mesher.hpp"
#include "ffcube/scene/obj_loader.hpp"
#include "support/temp_files.hpp"

namespace fs = std::filesystem;
using namespace ffcube;

namespace {

const fs::path kScenes = fs::path(FFCUBE_SOURCE_DIR) / "tests" / "data" / "scenes";

// The message of the InputError f throws, or a marker that no InputError came.
const auto error_of = test::input_error_of;

MtlResolver no_mtl() {
    return [](const std::string&) { return std::optional<std::string>(); };
}

ObjModel parse(std::string_view text) { return parse_obj(text, "t.obj", no_mtl()); }

// A scratch directory for generated files (binary garbage, huge tokens), removed at the end.
using TempDir = test::TempFiles;

struct BadCase {
    const char* file;
    const char* message;  // expected substring: file (and line) and the rule
};

class BadObj : public testing::TestWithParam<BadCase> {};

TEST_P(BadObj, IsRefusedNamingFileLineAndRule) {
    const BadCase c = GetParam();
    const std::string message = error_of([&] { load_obj(kScenes / "bad" / c.file); });
    EXPECT_NE(message.find(c.message), std::string::npos) << "got: " << message;
}

INSTANTIATE_TEST_SUITE_P(
    Issue2, BadObj,
    testing::Values(
        BadCase{"empty.obj", "empty.obj: no faces: the scene has no geometry"},
        BadCase{"comments_only.obj", "comments_only.obj: no faces: the scene has no geometry"},
        BadCase{"no_faces.obj", "no_faces.obj: no faces: the scene has no geometry"},
        BadCase{"index_zero.obj", "index_zero.obj:6: face index 0 is invalid (OBJ indices start at 1)"},
        BadCase{"index_out_of_range.obj", "index_out_of_range.obj:5: face index 9 is out of range (the file defines 4 vertices)"},
        BadCase{"negative_index_before_start.obj", "negative_index_before_start.obj:5: face index -5 is out of range"},
        BadCase{"nan_coordinate.obj", "nan_coordinate.obj:2: 'nan' is not a finite number"},
        BadCase{"inf_coordinate.obj", "inf_coordinate.obj:3: '-inf' is not a finite number"},
        BadCase{"overflow_float.obj", "overflow_float.obj:2: '1e39' is too large"},
        BadCase{"overflow_double.obj", "overflow_double.obj:3: '1e400' overflows a double"},
        BadCase{"not_a_number.obj", "not_a_number.obj:3: 'zero' is not a number"},
        BadCase{"two_vertex_face.obj", "two_vertex_face.obj:6: a face needs at least 3 vertices, this one has 2"},
        // A file cut in the middle of a statement is refused by the rule that statement breaks;
        // one cut between statements, or inside a number that still reads, is valid OBJ.
        BadCase{"truncated.obj", "truncated.obj:6: 'v' needs 3 coordinates, found 2"},
        BadCase{"kd_above_one.obj", "kd_above_one.mtl:3: Kd '1.5' must be within [0,1]"},
        BadCase{"kd_negative.obj", "kd_negative.mtl:2: Kd '-0.1' must be within [0,1]"},
        BadCase{"kd_nan.obj", "kd_nan.mtl:2: 'nan' is not a finite number (Kd"},
        BadCase{"ke_negative.obj", "ke_negative.mtl:3: Ke '-2' must be >= 0"},
        BadCase{"ke_nan.obj", "ke_nan.mtl:2: 'NaN' is not a finite number (Ke"},
        BadCase{"ke_inf.obj", "ke_inf.mtl:2: 'inf' is not a finite number (Ke"}),
    [](const testing::TestParamInfo<BadCase>& case_info) {
        std::string name = case_info.param.file;
        return name.substr(0, name.find('.'));
    });

TEST(BadInput, OnlyDegenerateFacesLoadButTheMesherRefuses) {
    const ObjModel model = load_obj(kScenes / "bad" / "degenerate_only.obj");
    EXPECT_EQ(model.faces.size(), 3u);
    const std::string message = error_of([&] { build_scene(model, MeshOptions{}); });
    EXPECT_NE(message.find("degenerate_only.obj: no faces with non-zero area (all 3 faces are degenerate)"),
              std::string::npos)
        << message;
}

TEST(BadInput, MissingFileNamesThePath) {
    const fs::path p = kScenes / "bad" / "does_not_exist.obj";
    const std::string message = error_of([&] { load_obj(p); });
    EXPECT_NE(message.find(p.string() + ": cannot read the scene: no such file"), std::string::npos) << message;
}

TEST(BadInput, DirectoryIsNotAnObjFile) {
    const fs::path p = kScenes / "bad";
    const std::string message = error_of([&] { load_obj(p); });
    EXPECT_NE(message.find(p.string() + ": is a directory, not an OBJ file"), std::string::npos) << message;
}

TEST(BadInput, BinaryGarbageWithNulIsNotAnObjFile) {
    const TempDir dir;
    std::string bytes = "\x89PNG\r\n\x1a\n";
    bytes += std::string("\0\0\0\rIHDR", 8);
    const fs::path p = dir.write("garbage.obj", bytes);
    const std::string message = error_of([&] { load_obj(p); });
    // The NUL bytes follow the second '\n': line 3.
    EXPECT_NE(message.find("garbage.obj:3: not an OBJ file (binary data: a NUL byte)"), std::string::npos) << message;
}

TEST(BadInput, ControlBytesWhereAKeywordShouldBeIsNotAnObjFile) {
    const std::string message = error_of([] { parse("v 0 0 0\n\x01\x7f\x02\x03 x\n"); });
    EXPECT_NE(message.find("t.obj:2: not an OBJ file"), std::string::npos) << message;
}

TEST(BadInput, MegabyteTokenIsRefusedWithItsLine) {
    const TempDir dir;
    const fs::path p = dir.write("huge_token.obj", "# fine\n" + std::string(1 << 20, 'x') + "\n");
    const std::string message = error_of([&] { load_obj(p); });
    EXPECT_NE(message.find("huge_token.obj:2: a token of 1048576 bytes is longer than the limit of 4096 bytes"),
              std::string::npos)
        << message.substr(0, 300);
}

TEST(BadInput, LongNumberTokenIsRefused) {
    const std::string message = error_of([] { parse("v 0 0 " + std::string(5000, '1') + "\nf 1 1 1\n"); });
    EXPECT_NE(message.find("t.obj:1: a token of 5000 bytes"), std::string::npos) << message;
}

TEST(BadInput, FaceVertexThatIsNotAnIndex) {
    EXPECT_NE(error_of([] { parse("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 x/1\n"); })
                  .find("t.obj:4: face vertex 'x/1' is not an index"),
              std::string::npos);
    EXPECT_NE(error_of([] { parse("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 /1\n"); }).find("t.obj:4: face vertex '/1'"),
              std::string::npos);
}

TEST(BadInput, HugeIndexIsOutOfRangeNotWrapped) {
    // 2^32 + 1 would wrap to index 0 in 32 bits; 1e30 does not fit 64 bits at all.
    EXPECT_NE(error_of([] { parse("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 4294967297\n"); }).find("t.obj:4: face index 4294967297 is out of range"),
              std::string::npos);
    EXPECT_NE(error_of([] { parse("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 1000000000000000000000000000000\n"); })
                  .find("t.obj:4: face index '1000000000000000000000000000000' is out of range"),
              std::string::npos);
}

TEST(BadInput, MtlRulesNameTheMtlLine) {
    std::vector<Material> m;
    EXPECT_NE(error_of([&] { parse_mtl("Kd 0.5\n", "m.mtl", m); }).find("m.mtl:1: 'Kd' before any 'newmtl'"),
              std::string::npos);
    EXPECT_NE(error_of([&] { parse_mtl("newmtl a\nKd 0.1 0.2\n", "m.mtl", m); }).find("m.mtl:2: 'Kd' takes 1 or 3 numbers"),
              std::string::npos);
    EXPECT_NE(error_of([&] { parse_mtl("newmtl a\nKe 1 1 1e39\n", "m.mtl", m); }).find("m.mtl:2: '1e39' is too large"),
              std::string::npos);
    EXPECT_NE(error_of([&] { parse_mtl("newmtl a\nKd 1.0000001\n", "m.mtl", m); }).find("m.mtl:2: Kd '1.0000001' must be within [0,1]"),
              std::string::npos);
}

// The plain unit square in z = 0, counter-clockwise from +z.
void expect_unit_square(const ObjModel& m, const std::string& object) {
    ASSERT_EQ(m.positions.size(), 4u);
    EXPECT_EQ(m.positions[0], Vec3(0, 0, 0));
    EXPECT_EQ(m.positions[1], Vec3(1, 0, 0));
    EXPECT_EQ(m.positions[2], Vec3(1, 1, 0));
    EXPECT_EQ(m.positions[3], Vec3(0, 1, 0));
    ASSERT_EQ(m.faces.size(), 1u);
    EXPECT_EQ(m.faces[0].v, (std::vector<std::uint32_t>{0, 1, 2, 3}));
    ASSERT_EQ(m.objects.size(), 1u);
    EXPECT_EQ(m.objects[0], object);
}

TEST(ValidInput, CrlfLineEnds) {
    const ObjModel m = load_obj(kScenes / "good" / "crlf.obj");
    expect_unit_square(m, "a");
    EXPECT_EQ(m.faces[0].line, 7u);
    EXPECT_TRUE(m.warnings.empty());
}

TEST(ValidInput, Utf8ByteOrderMark) {
    // Without stripping the BOM, "\xEF\xBB\xBFo" would be an unknown keyword and the object "default".
    const ObjModel m = load_obj(kScenes / "good" / "bom.obj");
    expect_unit_square(m, "a");
    EXPECT_TRUE(m.warnings.empty());
}

TEST(ValidInput, TabsAndRepeatedWhitespace) { expect_unit_square(load_obj(kScenes / "good" / "tabs.obj"), "a"); }

TEST(ValidInput, NoFinalNewline) { expect_unit_square(load_obj(kScenes / "good" / "no_final_newline.obj"), "a"); }

TEST(ValidInput, NegativeIndicesCountBackFromTheLineBefore) {
    const ObjModel m = load_obj(kScenes / "good" / "negative_indices.obj");
    ASSERT_EQ(m.faces.size(), 2u);
    EXPECT_EQ(m.faces[0].v, (std::vector<std::uint32_t>{0, 1, 2, 3}));
    EXPECT_EQ(m.faces[1].v, (std::vector<std::uint32_t>{4, 5, 6, 7}));
    EXPECT_EQ(m.objects, (std::vector<std::string>{"a", "b"}));
    EXPECT_EQ(m.faces[1].object, 1u);
}

TEST(ValidInput, SlashFormsKeepThePositionIndex) {
    const ObjModel m = load_obj(kScenes / "good" / "slashes.obj");
    ASSERT_EQ(m.faces.size(), 3u);
    EXPECT_EQ(m.faces[0].v, (std::vector<std::uint32_t>{0, 1, 2}));
    EXPECT_EQ(m.faces[1].v, (std::vector<std::uint32_t>{0, 2, 3}));
    EXPECT_EQ(m.faces[2].v, (std::vector<std::uint32_t>{0, 1, 2}));
    EXPECT_TRUE(m.warnings.empty());  // vt and vn are known statements, silently ignored
}

TEST(ValidInput, PathsAndMaterialLibraryWithSpaces) {
    const ObjModel m = load_obj(kScenes / "good" / "dir with space" / "scene with space.obj");
    EXPECT_TRUE(m.warnings.empty()) << m.warnings.front();
    ASSERT_EQ(m.materials.size(), 2u);
    EXPECT_EQ(m.materials[1].name, "red paint");
    EXPECT_EQ(m.materials[1].kd, Vec3(0.8, 0.1, 0.1));
    EXPECT_EQ(m.faces[0].material, 1u);
    EXPECT_EQ(m.objects, (std::vector<std::string>{"floor"}));
}

TEST(ValidInput, GroupsNameObjectsWhenThereIsNoO) {
    const ObjModel m = load_obj(kScenes / "good" / "groups.obj");
    EXPECT_EQ(m.objects, (std::vector<std::string>{"first", "second"}));
    ASSERT_EQ(m.faces.size(), 3u);
    EXPECT_EQ(m.faces[0].object, 0u);
    EXPECT_EQ(m.faces[1].object, 1u);
    EXPECT_EQ(m.faces[2].object, 0u);
}

TEST(ValidInput, ObjectsWinOverGroupsAndUnnamedFacesAreDefault) {
    const ObjModel m = parse("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\ng grp\no wall\nf 1 2 3\ng other\nf 1 2 3\n");
    EXPECT_EQ(m.objects, (std::vector<std::string>{"default", "wall"}));
    EXPECT_EQ(m.faces[0].object, 0u);
    EXPECT_EQ(m.faces[1].object, 1u);
    EXPECT_EQ(m.faces[2].object, 1u);
}

TEST(ValidInput, MaterialsNameObjectsWhenThereIsNoOAndNoG) {
    // Faces before the first 'usemtl' belong to "default".
    const ObjModel m = parse("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\nusemtl red\nf 1 2 3\nusemtl white\nf 1 2 3\n"
                             "usemtl red\nf 1 2 3\n");
    EXPECT_EQ(m.objects, (std::vector<std::string>{"default", "red", "white"}));
    ASSERT_EQ(m.faces.size(), 4u);
    EXPECT_EQ(m.faces[0].object, 0u);
    EXPECT_EQ(m.faces[1].object, 1u);
    EXPECT_EQ(m.faces[2].object, 2u);
    EXPECT_EQ(m.faces[3].object, 1u);
}

// A box's faces listed before its 'g' line (as in some widely used Cornell box files), one
// material per box: auto takes the groups, which are off by one; --objects-by material is right.
constexpr std::string_view kGroupsAfterFaces =
    "v 0 0 0\nv 1 0 0\nv 0 1 0\n"
    "usemtl short\nf 1 2 3\nf 1 3 2\ng short_block\n"
    "usemtl tall\nf 1 2 3\nf 1 3 2\ng tall_block\n"
    "o extra\n";

TEST(ValidInput, ObjectsByChoosesTheStatement) {
    const auto objects = [](ObjObjectsBy by) {
        const ObjModel m = parse_obj(kGroupsAfterFaces, "t.obj", no_mtl(), {by});
        std::vector<std::string> per_face;
        for (const ObjFace& f : m.faces) per_face.push_back(m.objects[f.object]);
        return per_face;
    };
    using V = std::vector<std::string>;
    // The file has an 'o' (after every face): auto takes 'o', so every face is "default".
    EXPECT_EQ(objects(ObjObjectsBy::automatic), (V{"default", "default", "default", "default"}));
    EXPECT_EQ(objects(ObjObjectsBy::o), (V{"default", "default", "default", "default"}));
    EXPECT_EQ(objects(ObjObjectsBy::g), (V{"default", "default", "short_block", "short_block"}));
    EXPECT_EQ(objects(ObjObjectsBy::material), (V{"short", "short", "tall", "tall"}));
    // Without the 'o', auto takes the groups.
    const std::string no_o(kGroupsAfterFaces.substr(0, kGroupsAfterFaces.find("o extra")));
    const ObjModel m = parse(no_o);
    EXPECT_EQ(m.objects, (std::vector<std::string>{"default", "short_block"}));
}

TEST(ValidInput, ObjectsByMaterialWithoutAnyUsemtlIsOneDefaultObject) {
    const ObjModel m = parse_obj("o a\nv 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n", "t.obj", no_mtl(), {ObjObjectsBy::material});
    EXPECT_EQ(m.objects, (std::vector<std::string>{"default"}));
}

TEST(BadInput, ObjectsByNamesTheOptionAndTheChoices) {
    EXPECT_EQ(parse_objects_by("auto"), ObjObjectsBy::automatic);
    EXPECT_EQ(parse_objects_by("o"), ObjObjectsBy::o);
    EXPECT_EQ(parse_objects_by("g"), ObjObjectsBy::g);
    EXPECT_EQ(parse_objects_by("material"), ObjObjectsBy::material);
    EXPECT_EQ(error_of([] { parse_objects_by("groups"); }), "--objects-by 'groups': must be auto, o, g or material");
}

TEST(ValidInput, MissingMtlWarningNamesEveryPathTried) {
    const MtlResolver only_a = [](const std::string& name) -> std::optional<std::string> {
        if (name == "a.mtl") return std::string("newmtl ma\nKd 0.1\n");
        return std::nullopt;
    };
    const ObjModel m = parse_obj("mtllib a.mtl b c.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n", "dir/t.obj", only_a);
    ASSERT_EQ(m.warnings.size(), 1u);
    EXPECT_NE(m.warnings[0].find("dir/t.obj:1: material library 'a.mtl b c.mtl' not found (tried 'dir/a.mtl b c.mtl', "
                                 "'dir/a.mtl', 'dir/b', 'dir/c.mtl')"),
              std::string::npos)
        << m.warnings[0];
}

TEST(ValidInput, NoNamesAtAllGiveDefault) {
    const ObjModel m = parse("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n");
    EXPECT_EQ(m.objects, (std::vector<std::string>{"default"}));
}

TEST(ValidInput, MissingMtlWarnsAndUsesTheDefaultMaterial) {
    const ObjModel m = load_obj(kScenes / "good" / "missing_mtl.obj");
    ASSERT_EQ(m.warnings.size(), 2u);
    EXPECT_NE(m.warnings[0].find("missing_mtl.obj:1: material library 'nowhere.mtl' not found (tried '" +
                                 (kScenes / "good" / "nowhere.mtl").string() + "')"),
              std::string::npos)
        << m.warnings[0];
    EXPECT_NE(m.warnings[1].find("missing_mtl.obj:2: material 'm' is not defined"), std::string::npos) << m.warnings[1];
    EXPECT_EQ(m.faces[0].material, 0u);
    EXPECT_EQ(m.materials[0].kd, Vec3(0.5));
    EXPECT_EQ(m.materials[0].ke, Vec3(0.0));
}

TEST(ValidInput, UnknownMaterialWarnsAndUsesTheDefault) {
    const ObjModel m = load_obj(kScenes / "good" / "unknown_material.obj");
    ASSERT_EQ(m.warnings.size(), 1u);
    EXPECT_NE(m.warnings[0].find("unknown_material.obj:3: material 'nosuch' is not defined"), std::string::npos)
        << m.warnings[0];
    EXPECT_EQ(m.faces[0].material, 0u);
}

TEST(ValidInput, UnknownStatementsGiveOneWarningWithACount) {
    const ObjModel m = parse("v 0 0 0\nfoo 1\nv 1 0 0\nbar\nv 0 1 0\nf 1 2 3\nfoo 2\n");
    ASSERT_EQ(m.warnings.size(), 1u);
    EXPECT_NE(m.warnings[0].find("t.obj: ignored 3 statements with unknown keywords (the first, 'foo', on line 2)"),
              std::string::npos)
        << m.warnings[0];
}

TEST(ValidInput, NumbersWithSignsExponentsAndExtraValues) {
    // A 4th value (w) and vertex colours are allowed and ignored; '+' signs and exponents read.
    const ObjModel m = parse("v +1.5 -2e-3 .25 1.0\nv 1E2 0 0 0.1 0.2 0.3\nv 1e15 -1e15 0\nf 1 2 3\n");
    EXPECT_EQ(m.positions[0], Vec3(1.5, -2e-3, 0.25));
    EXPECT_EQ(m.positions[1], Vec3(100, 0, 0));
    EXPECT_EQ(m.positions[2], Vec3(1e15, -1e15, 0));  // the largest magnitude allowed
}

TEST(ValidInput, MtlOneValueMeansGreyAndOtherStatementsAreIgnored) {
    std::vector<Material> m;
    parse_mtl("# comment\r\nnewmtl grey\r\nNs 10\r\nKa 1 1 1\r\nKd 0.25\r\nKe 0 0 0\r\nillum 2\r\nnewmtl lamp\r\nKe 3 2 1",
              "m.mtl", m);
    ASSERT_EQ(m.size(), 2u);
    EXPECT_EQ(m[0].name, "grey");
    EXPECT_EQ(m[0].kd, Vec3(0.25));
    EXPECT_EQ(m[1].name, "lamp");
    EXPECT_EQ(m[1].kd, Vec3(0.5));  // not given: the default reflectance
    EXPECT_EQ(m[1].ke, Vec3(3, 2, 1));
}

TEST(ValidInput, MtlLibWithSeveralFiles) {
    const MtlResolver r = [](const std::string& name) -> std::optional<std::string> {
        if (name == "a.mtl") return std::string("newmtl ma\nKd 0.1\n");
        if (name == "b.mtl") return std::string("newmtl mb\nKd 0.2\n");
        return std::nullopt;
    };
    const ObjModel m = parse_obj("mtllib a.mtl b.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nusemtl mb\nf 1 2 3\n", "t.obj", r);
    EXPECT_TRUE(m.warnings.empty());
    ASSERT_EQ(m.materials.size(), 3u);
    EXPECT_EQ(m.materials[m.faces[0].material].name, "mb");
}

TEST(ValidInput, ForwardPositiveIndicesAreResolvedAtTheEnd) {
    const ObjModel m = parse("f 1 2 3\nv 0 0 0\nv 1 0 0\nv 0 1 0\n");
    EXPECT_EQ(m.faces[0].v, (std::vector<std::uint32_t>{0, 1, 2}));
}

}  // namespace
