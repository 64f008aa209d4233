// The pre-checks of the assimp path (scene/import_checks.hpp, issue 43): every hostile or
// defective PLY/glTF/GLB class is refused by load_model with the file, the header line or JSON
// path and the rule, before assimp reads it; valid files of every encoding still load to the
// same faces.
#include <gtest/gtest.h>

#include <sys/stat.h>
#include <unistd.h>

#include <cstring>
#include <filesystem>
#include <fstream>
#include <string>

#include "ffcube/core/error.hpp"
#include "ffcube/scene/import_checks.hpp"
#include "ffcube/scene/load_model.hpp"
#include "ffcube/scene/mesher.hpp"
#include "support/hostile_imports.hpp"
#include "support/temp_files.hpp"

namespace ffcube {
namespace {

namespace fs = std::filesystem;
using test::input_error_of;
using test::TempFiles;

TEST(ImportChecks, EveryHostileFileIsRefusedWithItsRule) {
    for (const test::HostileFile& f : test::hostile_files()) {
        SCOPED_TRACE(f.name);
        TempFiles t;
        const fs::path p = test::write_hostile(t.path(), f);
        const std::string m = input_error_of([&] { load_model(p); });
        EXPECT_NE(m.find(f.message), std::string::npos) << "expected: " << f.message << "\ngot: " << m;
        EXPECT_NE(m.find(f.name), std::string::npos) << m;  // the file is named
    }
}

TEST(ImportChecks, ACommentHoldingEndHeaderIsNamedInTheMessage) {
    TempFiles t;
    const std::string m = input_error_of([&] {
        load_model(t.write("c.ply", test::ply_header("ascii", 4, 2, "uchar int", "comment end_header\n") + test::kSquareAscii));
    });
    EXPECT_NE(m.find("the 'end_header' on line 9 is inside a comment"), std::string::npos) << m;
}

// The square through each encoding: 2 faces, area 1.
void expect_square(const ObjModel& m) {
    ASSERT_EQ(m.faces.size(), 2u);
    MeshOptions o;
    o.subdivide = false;
    EXPECT_NEAR(build_scene(m, o).total_area(), 1.0, 1e-12);
}

TEST(ImportChecks, AnAsciiListCountMustFitItsType) {
    // 300 entries under a uchar count: assimp would store the count as 44.
    TempFiles t;
    std::string faces = "300";
    for (int i = 0; i < 300; ++i) faces += " 0";
    const std::string m = input_error_of([&] {
        load_model(t.write("u8.ply", test::ply_header("ascii", 4, 1) + "0 0 0\n1 0 0\n1 1 0\n0 1 0\n" + faces + "\n"));
    });
    EXPECT_NE(m.find("u8.ply:14: element 'face' record 1: list 'vertex_indices' count 300 does not fit its count type (at most 255)"),
              std::string::npos)
        << m;
}

TEST(ImportChecks, ValidPlyOfEveryEncodingLoads) {
    TempFiles t;
    expect_square(load_model(t.write("a.ply", test::ply_header("ascii", 4, 2) + test::kSquareAscii)));
    // CRLF line ends, a comment and obj_info, trailing blank lines.
    std::string crlf = "ply\r\nformat ascii 1.0\r\ncomment by hand\r\nobj_info x\r\nelement vertex 4\r\nproperty float x\r\n"
                       "property float y\r\nproperty float z\r\nelement face 2\r\nproperty list uchar int vertex_indices\r\n"
                       "end_header\r\n0 0 0\r\n1 0 0\r\n1 1 0\r\n0 1 0\r\n3 0 1 2\r\n3 0 2 3\r\n\r\n";
    expect_square(load_model(t.write("crlf.ply", crlf)));
    std::string le = test::ply_header("binary_little_endian", 4, 2) + test::square_binary_vertices();
    for (int f = 0; f < 2; ++f) {
        le += '\3';
        for (std::int32_t i : {0, 1 + f, 2 + f}) test::append_le(le, i);
    }
    expect_square(load_model(t.write("le.ply", le)));
    // Big-endian: every 4-byte value most significant byte first.
    const auto be32 = [](std::string& out, std::uint32_t v) {
        for (int k = 3; k >= 0; --k) out += static_cast<char>((v >> (8 * k)) & 0xff);
    };
    std::string be = test::ply_header("binary_big_endian", 4, 2);
    for (float x : {0.f, 0.f, 0.f, 1.f, 0.f, 0.f, 1.f, 1.f, 0.f, 0.f, 1.f, 0.f}) {
        std::uint32_t u = 0;
        std::memcpy(&u, &x, 4);
        be32(be, u);
    }
    for (int f = 0; f < 2; ++f) {
        be += '\3';
        for (std::uint32_t i : {0, 1 + f, 2 + f}) be32(be, i);
    }
    expect_square(load_model(t.write("be.ply", be)));
}

TEST(ImportChecks, ValidGltfEmbeddedExternalAndBinaryLoad) {
    TempFiles t;
    expect_square(load_model(t.write("s.gltf", test::square_gltf({}))));
    expect_square(load_model(t.write("s.glb", test::square_glb())));
    // An external buffer beside the file, in a subfolder, through a symlink that stays inside.
    test::SquareGltf g;
    fs::create_directory(t.path() / "data");
    t.write("data/square.bin", test::square_gltf_data(g));
    g.buffer_uri = "data/square.bin";
    expect_square(load_model(t.write("ext.gltf", test::square_gltf(g))));
    fs::create_symlink("data/square.bin", t.path() / "link.bin");
    g.buffer_uri = "link.bin";
    expect_square(load_model(t.write("link.gltf", test::square_gltf(g))));
    // assimp 5.2.5 opens a URI as written, without decoding percent-escapes: so does the check
    // (which also keeps the decoded spelling inside the folder).
    g.buffer_uri = "data/squ%61re.bin";
    EXPECT_NE(input_error_of([&] { load_model(t.write("escaped.gltf", test::square_gltf(g))); })
                  .find("data/squ%61re.bin: cannot read the buffer: no such file"),
              std::string::npos);
}

TEST(ImportChecks, BufferUrisStayInsideTheModelsFolder) {
    TempFiles t;
    fs::create_directory(t.path() / "model");
    t.write("outside.bin", test::square_gltf_data({}));
    fs::create_symlink(t.path() / "outside.bin", t.path() / "model" / "link.bin");
    test::SquareGltf g;
    const auto refused = [&](const std::string& uri) {
        g.buffer_uri = uri;
        return input_error_of([&] { load_model(t.write("model/m.gltf", test::square_gltf(g))); });
    };
    EXPECT_NE(refused("link.bin").find("outside the model's folder"), std::string::npos);     // a symlink pointing out
    EXPECT_NE(refused("%2e%2e/outside.bin").find("'..' leaves"), std::string::npos);           // escaped dots
    EXPECT_NE(refused("sub/../../outside.bin").find("'..' leaves"), std::string::npos);
    EXPECT_NE(refused("absent.bin").find("cannot read the buffer: no such file"), std::string::npos);
    EXPECT_NE(refused(".").find("the model's folder itself"), std::string::npos) << refused(".");
    fs::create_directory(t.path() / "model" / "sub");
    EXPECT_NE(refused("sub").find("model/sub: is a directory, not a glTF buffer file"), std::string::npos) << refused("sub");
    EXPECT_NE(refused("a\\\\b.bin").find("backslash"), std::string::npos);  // JSON "a\\b.bin": the URI a\b.bin
    // Image URIs are checked the same way (assimp records them as texture paths).
    std::string j = test::square_gltf({});
    j.replace(j.size() - 1, 1, R"(,"images":[{"uri":"../../etc/shadow.png"}]})");
    EXPECT_NE(input_error_of([&] { load_model(t.write("model/img.gltf", j)); }).find("images[0].uri: uri '../../etc/shadow.png'"),
              std::string::npos);
}

TEST(ImportChecks, GlbHeaderAndChunksAgainstTheFileSize) {
    TempFiles t;
    std::string glb = test::square_glb();
    std::string cut = glb.substr(0, glb.size() - 10);
    EXPECT_NE(input_error_of([&] { load_model(t.write("cut.glb", cut)); }).find("cut.glb: GLB header: length"), std::string::npos);
    std::string v1 = glb;
    v1[4] = 1;
    EXPECT_NE(input_error_of([&] { load_model(t.write("v1.glb", v1)); }).find("version 1; only glTF 2.0 is read"), std::string::npos);
    EXPECT_NE(input_error_of([&] { load_model(t.write("text.glb", "not a glb at all")); }).find("no 'glTF' magic"), std::string::npos);
}

TEST(ImportChecks, ProblemsOfTheJsonItselfAreNamed) {
    TempFiles t;
    const auto m = [&](const std::string& name, const std::string& text) { return input_error_of([&] { load_model(t.write(name, text)); }); };
    EXPECT_NE(m("a.gltf", "{\"asset\":").find("a.gltf: (JSON): not valid JSON"), std::string::npos);
    EXPECT_NE(m("b.gltf", R"({"asset":{"version":"1.0"}})").find("b.gltf: asset.version: \"1.0\": only glTF 2.0 is read"),
              std::string::npos);
    std::string big = test::square_gltf({});
    big.replace(big.find("\"count\":4"), 9, "\"count\":4294967300");
    EXPECT_NE(m("c.gltf", big).find("accessors[0].count: 4294967300 must be an integer in [0, 2^32)"), std::string::npos);
    std::string frac = test::square_gltf({});
    frac.replace(frac.find("\"count\":4"), 9, "\"count\":4.0");
    EXPECT_NE(m("d.gltf", frac).find("accessors[0].count: 4.0 must be an integer"), std::string::npos);
    std::string cycle = test::square_gltf({});
    cycle.replace(cycle.find(R"({"name":"square","mesh":0})"), 26, R"({"name":"square","mesh":0,"children":[1]},{"children":[2]},{"children":[1]})");
    EXPECT_NE(m("e.gltf", cycle).find("nodes[2].children[0]: nodes[1] has a second parent"), std::string::npos);
    std::string mode = test::square_gltf({});
    mode.replace(mode.find("\"indices\":1"), 11, "\"indices\":1,\"mode\":9");
    EXPECT_NE(m("f.gltf", mode).find("meshes[0].primitives[0].mode: 9 is not a primitive mode"), std::string::npos);
}

TEST(ImportChecks, ContentDecidesNotOnlyTheExtension) {
    // assimp also picks its importer by signature: a PLY under another name is checked as PLY.
    EXPECT_EQ(sniff_import_format("ply\nformat ascii 1.0\n", ".dae"), ImportFormat::ply);
    EXPECT_EQ(sniff_import_format("glTF\x02", ".bin"), ImportFormat::glb);
    EXPECT_EQ(sniff_import_format(" {\"asset\":{}}", ".json"), ImportFormat::gltf);
    EXPECT_EQ(sniff_import_format("<COLLADA>", ".dae"), ImportFormat::other);
    EXPECT_EQ(sniff_import_format("solid", ".ply"), ImportFormat::ply);  // then refused: no magic
}

TEST(ImportChecks, AnErrorOfTheChildKeepsItsClass) {
    // Passes the pre-check; assimp and the collector run in the child, and the collector's
    // refusal (a coordinate above 1e15) arrives as the InputError it was, with its words.
    TempFiles t;
    const std::string m = input_error_of(
        [&] { load_model(t.write("far.ply", test::ply_header("ascii", 4, 2) + "0 0 0\n1e30 0 0\n1 1 0\n0 1 0\n3 0 1 2\n3 0 2 3\n")); });
    EXPECT_NE(m.find("far.ply: mesh"), std::string::npos) << m;
    EXPECT_NE(m.find("is not finite with magnitude at most 1e15"), std::string::npos) << m;
}

TEST(ImportChecks, Base64IsStrict) {
    std::string out;
    EXPECT_TRUE(decode_base64("aGVsbG8=", out));
    EXPECT_EQ(out, "hello");
    EXPECT_TRUE(decode_base64("", out));
    EXPECT_FALSE(decode_base64("aGVsbG8", out));   // not a multiple of 4
    EXPECT_FALSE(decode_base64("aGV=bG8=", out));  // '=' inside
    EXPECT_FALSE(decode_base64("aGVsbG8*", out));
}

}  // namespace
}  // namespace ffcube
