// The render layer: shading patches to vertices, the default camera, tone mapping, pictures on a
// headless GL context (llvmpipe), and the EXR, PNG and PLY writers read back by other code.
#include <gtest/gtest.h>

#include <OpenEXR/ImfChannelList.h>
#include <OpenEXR/ImfFrameBuffer.h>
#include <OpenEXR/ImfHeader.h>
#include <OpenEXR/ImfInputFile.h>
#define STB_IMAGE_IMPLEMENTATION
#define STB_IMAGE_STATIC
#include <stb/stb_image.h>

#include <glm/geometric.hpp>

#include <cmath>
#include <cstring>
#include <fstream>
#include <numbers>
#include <sstream>

#include "ffcube/core/error.hpp"
#include "ffcube/io/ply.hpp"
#include "ffcube/render/renderer.hpp"
#include "support/scenes.hpp"

namespace ffcube {
namespace {

using test::inward_box;
using test::make_scene;
using test::square_z;

std::filesystem::path temp_path(const std::string& name) {
    return std::filesystem::temp_directory_path() / ("ffcube_render_" + std::to_string(::getpid()) + "_" + name);
}

TEST(Shading, FlatKeepsEachPatchValue) {
    const Scene s = make_scene({square_z("a", 0, true)}, 0.5);  // 2×2 patches
    ASSERT_EQ(s.size(), 4u);
    std::vector<Vec3> v{Vec3(1), Vec3(2), Vec3(3), Vec3(4)};
    const ShadedMesh m = shade_patches(s, v, Shading::Flat);
    ASSERT_EQ(m.face_sizes.size(), 4u);
    ASSERT_EQ(m.positions.size(), 16u);  // unshared corners
    for (std::size_t f = 0; f < 4; ++f)
        for (std::size_t c = 0; c < 4; ++c) EXPECT_EQ(m.values[m.face_indices[4 * f + c]], v[f]);
}

TEST(Shading, SmoothAveragesWithinASurfaceByArea) {
    // One surface of unequal patches: a 1.5 × 1 rectangle at edge bound 0.5 (3 × 2 patches of
    // 0.25) and a 1.5 × 0.2 strip above it (3 patches of 0.1), two faces of one object. Every
    // output vertex must hold Σ A_i v_i / Σ A_i over the patches with a corner at its position
    // (brute force here), including the vertices the two faces share.
    test::NamedPolygon wide{"a", {Vec3(0, 0, 0), Vec3(1.5, 0, 0), Vec3(1.5, 1, 0), Vec3(0, 1, 0)}};
    test::NamedPolygon strip{"a", {Vec3(0, 1, 0), Vec3(1.5, 1, 0), Vec3(1.5, 1.2, 0), Vec3(0, 1.2, 0)}};
    const Scene s = make_scene({wide, strip}, 0.5);
    std::vector<Vec3> v(s.size());
    for (std::size_t i = 0; i < s.size(); ++i) v[i] = Vec3(1.0 + static_cast<double>(i * i), 2.0, -1.0 * static_cast<double>(i));
    const ShadedMesh m = shade_patches(s, v, Shading::Smooth);
    EXPECT_EQ(m.positions.size(), 4u * 4u);  // grid points x ∈ {0, .5, 1, 1.5} × y ∈ {0, .5, 1, 1.2}
    for (std::size_t k = 0; k < m.positions.size(); ++k) {
        Vec3 sum(0.0);
        double area = 0.0;
        for (std::size_t i = 0; i < s.size(); ++i)
            for (std::uint32_t c = 0; c < s.patches[i].count; ++c)
                if (glm::length(s.positions[s.patches[i].v[c]] - m.positions[k]) < 1e-12) {
                    sum += s.patches[i].area * v[i];
                    area += s.patches[i].area;
                }
        for (int c = 0; c < 3; ++c) EXPECT_NEAR(m.values[k][c], sum[c] / area, 1e-12 * std::abs(sum[c] / area)) << k;
    }
    for (std::uint32_t i : m.face_indices) EXPECT_LT(i, m.positions.size());
}

TEST(Shading, CornersBetweenWallsStaySharp) {
    // A closed box, one value per wall: walls meet at 90° and are different objects, so every
    // vertex takes exactly its own wall's value and the walls do not bleed into each other.
    const Scene s = make_scene(inward_box(1, 1, 1), 0.5);
    std::vector<Vec3> v(s.size());
    for (std::size_t i = 0; i < s.size(); ++i) v[i] = Vec3(static_cast<double>(s.patches[i].object));
    const ShadedMesh m = shade_patches(s, v, Shading::Smooth);
    EXPECT_EQ(m.positions.size(), 6u * 9u);  // 3×3 grid points per wall, none merged across walls
    std::size_t at = 0;
    for (std::size_t f = 0; f < m.face_sizes.size(); ++f)
        for (std::uint8_t c = 0; c < m.face_sizes[f]; ++c) EXPECT_EQ(m.values[m.face_indices[at++]], v[f]);
}

TEST(Camera, OpenSideAndClosedScenes) {
    // A box without its z = 0 wall: looked into from −z, outside, framing a 1×1 cross-section.
    std::vector<test::NamedPolygon> walls = inward_box(1, 1, 1);
    walls.erase(walls.begin());  // z0
    const Camera open = default_camera(make_scene(walls, 1.0));
    EXPECT_LT(open.eye.z, 0.0);
    EXPECT_DOUBLE_EQ(open.eye.x, 0.5);
    EXPECT_DOUBLE_EQ(open.eye.y, 0.5);
    // tan(fov/2) × distance = 1.03 × half the cross-section.
    EXPECT_NEAR(std::tan(open.fov_degrees * std::numbers::pi / 360) * -open.eye.z, 1.03 * 0.5, 1e-12);
    // Closed: the eye is inside the box.
    const Camera closed = default_camera(make_scene(inward_box(1, 1, 1), 1.0));
    for (int k = 0; k < 3; ++k) {
        EXPECT_GT(closed.eye[k], 0.0);
        EXPECT_LT(closed.eye[k], 1.0);
    }
}

TEST(Camera, ParseAndRefuse) {
    const Camera c = parse_camera("1,2,3,4,5,6,45");
    EXPECT_EQ(c.eye, Vec3(1, 2, 3));
    EXPECT_EQ(c.target, Vec3(4, 5, 6));
    EXPECT_EQ(c.fov_degrees, 45.0);
    EXPECT_EQ(parse_camera("0,0,0,0,0,1").fov_degrees, 39.3);
    for (const char* bad : {"1,2,3", "1,2,3,4,5,x", "0,0,0,0,0,0", "0,0,0,0,0,1,180", "0,0,0,0,0,1,nan", "1,2,3,4,5,6,7,8"})
        EXPECT_THROW(parse_camera(bad), InputError) << bad;
}

TEST(ToneMapping, SrgbAndAutoExposure) {
    EXPECT_EQ(encode_srgb8(0.0, 1.0), 0);
    EXPECT_EQ(encode_srgb8(1.0, 1.0), 255);
    EXPECT_EQ(encode_srgb8(7.0, 1.0), 255);  // clipped
    // sRGB(0.5) = 1.055 × 0.5^(1/2.4) − 0.055 = 0.735357 → 187.5 → 188; exposure multiplies first.
    EXPECT_EQ(encode_srgb8(0.5, 1.0), 188);
    EXPECT_EQ(encode_srgb8(0.25, 2.0), 188);
    // Linear segment: 12.92 × 0.001 × 255 = 3.29 → 3.
    EXPECT_EQ(encode_srgb8(0.001, 1.0), 3);
    // Weighted median: weights 1, 1, 5 → the value of weight 5 is the median.
    const std::vector<double> lum{1.0, 2.0, 4.0}, w{1.0, 1.0, 5.0};
    EXPECT_DOUBLE_EQ(auto_exposure(lum, w), 0.3 / 4.0);
    const std::vector<double> zero{0.0, 0.0};
    EXPECT_EQ(auto_exposure(zero, std::vector<double>{1.0, 1.0}), 1.0);
}

// A unit square at z = 0 facing −z, split into two objects (left half x < 0.5, right half).
Scene two_halves() {
    test::NamedPolygon left{"left", {Vec3(0, 0, 0), Vec3(0, 1, 0), Vec3(0.5, 1, 0), Vec3(0.5, 0, 0)}};
    test::NamedPolygon right{"right", {Vec3(0.5, 0, 0), Vec3(0.5, 1, 0), Vec3(1, 1, 0), Vec3(1, 0, 0)}};
    return make_scene({left, right}, 0.5);
}

RenderSettings looking_at_square(double eye_z) {
    RenderSettings rs;
    rs.width = rs.height = 64;
    rs.camera.eye = Vec3(0.5, 0.5, eye_z);
    rs.camera.target = Vec3(0.5, 0.5, 0);
    rs.camera.fov_degrees = 40;
    rs.back_face_value = Vec3(0.125, 0.25, 0.5);
    return rs;
}

TEST(Renderer, FlatPixelsHoldThePatchValueExactly) {
    const Scene s = two_halves();
    std::vector<Vec3> v(s.size());
    for (std::size_t i = 0; i < s.size(); ++i)
        v[i] = s.patches[i].object == 0 ? Vec3(1.0 / 3.0, 2.0 / 7.0, 0.1) : Vec3(5.0, 6.0 / 11.0, 1e-3);
    RenderSettings rs = looking_at_square(-2.0);
    rs.flat = true;
    auto ctx = create_headless_context(Backend::Auto);
    const Image img = render_mesh(*ctx, shade_patches(s, v, Shading::Flat), rs);
    ASSERT_EQ(img.width, 64);
    // Seen from −z with +y up, +x runs to the left of the picture: the "left" object (x < 0.5) is
    // on the right. Pixel (40, 32) lies at x ≈ 0.5 − (40.5 − 32)/32 × 2 tan 20° ≈ 0.31.
    const float* right_px = img.pixel(40, 32);
    const float* left_px = img.pixel(23, 32);
    for (int c = 0; c < 3; ++c) {
        EXPECT_EQ(right_px[c], static_cast<float>(v[0][c]));
        EXPECT_EQ(left_px[c], static_cast<float>(Vec3(5.0, 6.0 / 11.0, 1e-3)[c]));
    }
    EXPECT_EQ(right_px[3], 1.0f);
    EXPECT_EQ(img.pixel(0, 0)[3], 0.0f);  // background: the square spans 2 tan 20° × 2 = 1.46 > 1
    EXPECT_EQ(img.pixel(0, 0)[0], 0.0f);
}

TEST(Renderer, BackFacesShowTheNeutralValueAndDepthHidesWhatIsBehind) {
    const Scene s = two_halves();
    std::vector<Vec3> v(s.size(), Vec3(1.0));
    // From +z the square is seen from behind.
    RenderSettings rs = looking_at_square(2.0);
    auto ctx = create_headless_context(Backend::Auto);
    const Image back = render_mesh(*ctx, shade_patches(s, v, Shading::Smooth), rs);
    for (int c = 0; c < 3; ++c) EXPECT_EQ(back.pixel(32, 32)[c], static_cast<float>(rs.back_face_value[c]));
    // Two squares, the nearer one (z = −1, value 2) hides the farther one (z = 0, value 1),
    // whatever the drawing order.
    const Scene two = make_scene({square_z("far", 0, false), square_z("near", -1, false)}, 1.0);
    std::vector<Vec3> w{Vec3(1.0), Vec3(2.0)};
    const Image img = render_mesh(*ctx, shade_patches(two, w, Shading::Flat), looking_at_square(-3.0));
    EXPECT_EQ(img.pixel(32, 32)[0], 2.0f);
}

TEST(Renderer, SmoothShadingInterpolatesLinearly) {
    // One quad with vertex values equal to x: perspective-correct interpolation reproduces the
    // linear function, so a pixel shows the x of the point it sees (to the pixel: ±half a pixel
    // of 1.46/64 scene units, the footprint at the square).
    const Scene s = make_scene({square_z("q", 0, false)}, 1.0);
    ShadedMesh m = shade_patches(s, std::vector<Vec3>{Vec3(0.0)}, Shading::Smooth);
    for (std::size_t k = 0; k < m.positions.size(); ++k) m.values[k] = Vec3(m.positions[k].x);
    const RenderSettings rs = looking_at_square(-2.0);
    auto ctx = create_headless_context(Backend::Auto);
    const Image img = render_mesh(*ctx, m, rs);
    const double pixel = 2.0 * 2.0 * std::tan(20.0 * std::numbers::pi / 180) / 64;
    for (int px : {20, 32, 44}) {
        const double x = 0.5 - (px + 0.5 - 32) * pixel;  // +x to the left (seen from −z)
        EXPECT_NEAR(img.pixel(px, 32)[0], x, 1e-4) << px;
    }
}

TEST(ImageFiles, ExrHoldsTheFloatsUnchanged) {
    Image img;
    img.width = 3;
    img.height = 2;
    img.rgba = {0.f, 1.f, 2.f, 1.f, 1e-8f, 3.5e7f, 0.1f, 1.f, 0.3f, 0.6f, 0.9f, 0.f,
                5.f, 6.f, 7.f, 1.f, 1.f / 3, 2.f / 3, 1.f / 7, 1.f, 8.f, 9.f, 10.f, 1.f};
    const auto path = temp_path("t.exr");
    write_exr(path, img);
    Imf::InputFile in(path.c_str());
    const Imath::Box2i dw = in.header().dataWindow();
    ASSERT_EQ(dw.max.x - dw.min.x + 1, 3);
    ASSERT_EQ(dw.max.y - dw.min.y + 1, 2);
    for (const char* n : {"R", "G", "B", "A"}) {
        const Imf::Channel* ch = in.header().channels().findChannel(n);
        ASSERT_NE(ch, nullptr) << n;
        EXPECT_EQ(ch->type, Imf::FLOAT);
    }
    std::vector<float> back(img.rgba.size(), -1.f);
    Imf::FrameBuffer fb;
    const char* names[4] = {"R", "G", "B", "A"};
    for (int c = 0; c < 4; ++c)
        fb.insert(names[c], Imf::Slice(Imf::FLOAT, reinterpret_cast<char*>(back.data() + c), 16, 16 * 3));
    in.setFrameBuffer(fb);
    in.readPixels(dw.min.y, dw.max.y);
    EXPECT_EQ(back, img.rgba);
    std::filesystem::remove(path);
}

TEST(ImageFiles, PngIsTheToneMappedImage) {
    Image img;
    img.width = 2;
    img.height = 2;
    img.rgba = {0.f, 0.25f, 0.5f, 1.f, 1.f, 2.f, 0.001f, 1.f, 0.1f, 0.2f, 0.3f, 0.f, 0.4f, 0.45f, 0.05f, 1.f};
    const auto path = temp_path("t.png");
    const double exposure = 1.7;
    write_png(path, img, exposure);
    int w = 0, h = 0, n = 0;
    unsigned char* px = stbi_load(path.c_str(), &w, &h, &n, 4);
    ASSERT_NE(px, nullptr);
    ASSERT_EQ(w, 2);
    ASSERT_EQ(h, 2);
    for (int i = 0; i < 4; ++i) {
        for (int c = 0; c < 3; ++c) EXPECT_EQ(px[4 * i + c], encode_srgb8(img.rgba[4 * i + c], exposure)) << i << c;
        EXPECT_EQ(px[4 * i + 3], img.rgba[4 * i + 3] > 0.5f ? 255 : 0);
    }
    stbi_image_free(px);
    std::filesystem::remove(path);
}

TEST(ImageFiles, UnwritablePathIsAnIoErrorAndLeavesNothing) {
    Image img;
    img.width = img.height = 1;
    img.rgba = {1, 1, 1, 1};
    EXPECT_THROW(write_exr("/nonexistent_dir_ffcube/x.exr", img), IoError);
    EXPECT_THROW(write_png("/nonexistent_dir_ffcube/x.png", img, 1.0), IoError);
}

TEST(PlyFile, HeaderAndBinaryBodyReadBack) {
    PlyMesh m;
    m.positions = {Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(1, 1, 0), Vec3(0, 1, 0), Vec3(2, 0, 0)};
    m.colors = {{{1, 2, 3}}, {{4, 5, 6}}, {{7, 8, 9}}, {{10, 11, 12}}, {{255, 0, 128}}};
    m.values = {Vec3(0.5), Vec3(1.5), Vec3(2.5), Vec3(3.5), Vec3(4.5)};
    m.face_sizes = {4, 3};
    m.face_indices = {0, 1, 2, 3, 1, 4, 2};
    const auto path = temp_path("m.ply");
    write_ply(path, m, "test\nmesh");
    std::ifstream in(path, std::ios::binary);
    std::string line;
    std::vector<std::string> header;
    while (std::getline(in, line) && line != "end_header") header.push_back(line);
    ASSERT_EQ(line, "end_header");
    EXPECT_EQ(header[0], "ply");
    EXPECT_EQ(header[1], "format binary_little_endian 1.0");
    EXPECT_EQ(header[2], "comment test mesh");  // one line
    EXPECT_EQ(header[3], "element vertex 5");
    EXPECT_NE(std::find(header.begin(), header.end(), "element face 2"), header.end());
    EXPECT_NE(std::find(header.begin(), header.end(), "property list uchar uint vertex_indices"), header.end());
    // Vertex records: 3 floats, 3 uchar, 3 floats = 27 bytes.
    std::vector<char> body((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    ASSERT_EQ(body.size(), 5u * 27u + (1 + 4 * 4) + (1 + 3 * 4));
    for (std::size_t v = 0; v < 5; ++v) {
        float xyz[3], val[3];
        std::memcpy(xyz, &body[27 * v], 12);
        std::memcpy(val, &body[27 * v + 15], 12);
        for (int k = 0; k < 3; ++k) {
            EXPECT_EQ(xyz[k], static_cast<float>(m.positions[v][k]));
            EXPECT_EQ(val[k], static_cast<float>(m.values[v][k]));
            EXPECT_EQ(static_cast<std::uint8_t>(body[27 * v + 12 + k]), m.colors[v][k]);
        }
    }
    std::uint32_t last[3];
    EXPECT_EQ(body[27 * 5 + 17], 3);
    std::memcpy(last, &body[27 * 5 + 18], 12);
    EXPECT_EQ(last[0], 1u);
    EXPECT_EQ(last[1], 4u);
    EXPECT_EQ(last[2], 2u);
    std::filesystem::remove(path);
}

}  // namespace
}  // namespace ffcube
