// PNG and EXR files as the viewer writes them (render/image.hpp), read back through independent decoders.
#include <OpenEXR/ImfRgbaFile.h>
#include <gtest/gtest.h>

#define STB_IMAGE_STATIC
#define STB_IMAGE_IMPLEMENTATION
#include <stb/stb_image.h>

#include <filesystem>
#include <vector>

#include "cli/cli_util.hpp"
#include "ffcube/core/error.hpp"
#include "ffcube/render/image.hpp"

namespace ffcube {
namespace {

TEST(ImageIo, PngRoundTripsExactlyTopRowFirst) {
    test::TempDir dir;
    const std::vector<std::uint8_t> rgba = {255, 0, 0, 255, 0, 255, 0, 255, 0, 0, 255, 255,
                                            10,  20, 30, 255, 40, 50, 60, 255, 70, 80, 90, 255};
    const std::string path = dir / "a.png";
    write_png_rgba8(path, 3, 2, rgba);
    int w = 0, h = 0, n = 0;
    stbi_uc* data = stbi_load(path.c_str(), &w, &h, &n, 3);
    ASSERT_NE(data, nullptr);
    EXPECT_EQ(w, 3);
    EXPECT_EQ(h, 2);
    for (int i = 0; i < 6; ++i)
        for (int c = 0; c < 3; ++c) EXPECT_EQ(data[3 * i + c], rgba[4 * i + c]);
    stbi_image_free(data);
}

TEST(ImageIo, ExrRoundTripsWithinHalfPrecision) {
    test::TempDir dir;
    const std::vector<float> rgb = {0.0f, 1.0f, 53.407f, 0.001f, 0.5f, 2.25f};
    const std::string path = dir / "a.exr";
    write_exr(path, Image{2, 1, {rgb[0], rgb[1], rgb[2], 1.0f, rgb[3], rgb[4], rgb[5], 1.0f}});
    Imf::RgbaInputFile in(path.c_str());
    const Imath::Box2i dw = in.dataWindow();
    ASSERT_EQ(dw.max.x - dw.min.x + 1, 2);
    ASSERT_EQ(dw.max.y - dw.min.y + 1, 1);
    std::vector<Imf::Rgba> px(2);
    in.setFrameBuffer(px.data(), 1, 2);
    in.readPixels(dw.min.y, dw.max.y);
    for (int i = 0; i < 2; ++i) {
        const float got[3] = {px[i].r, px[i].g, px[i].b};
        // half: 11 significant bits, relative rounding error at most 2^-11.
        for (int c = 0; c < 3; ++c) EXPECT_NEAR(got[c], rgb[3 * i + c], std::abs(rgb[3 * i + c]) * 4.9e-4f);
    }
}

TEST(ImageIo, UnwritablePathLeavesNoFile) {
    test::TempDir dir;
    const std::string path = (dir.path() / "missing" / "a.png").string();
    const std::vector<std::uint8_t> rgba(4, 0);
    EXPECT_THROW(write_png_rgba8(path, 1, 1, rgba), IoError);
    EXPECT_FALSE(std::filesystem::exists(path));
}

}  // namespace
}  // namespace ffcube
