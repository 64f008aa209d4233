// Float RGBA images and writing them: OpenEXR (linear float) and PNG (tone-mapped 8-bit sRGB).
#pragma once

#include <cstdint>
#include <filesystem>
#include <span>
#include <vector>

#include "ffcube/geometry/polygon.hpp"

namespace ffcube {

// Linear float RGBA, row-major, row 0 at the top, 4 floats per pixel. Alpha is 1 where geometry
// was drawn and 0 on the background.
struct Image {
    int width = 0, height = 0;
    std::vector<float> rgba;

    const float* pixel(int x, int y) const { return &rgba[(static_cast<std::size_t>(y) * width + x) * 4]; }
};

// Rec. 709 luminance Y = 0.2126 R + 0.7152 G + 0.0722 B.
double luminance(const Vec3& rgb);

// The exposure a PNG (and a PLY's colours) gets when none is given: 0.3 / the weighted median of
// the luminances (a surface of median brightness shows at 0.3 linear, 0.58 in sRGB, leaving
// headroom for brighter ones before they clip); 1 when that median is 0. Weights ≥ 0.
double auto_exposure(std::span<const double> luminance, std::span<const double> weight);

// One display value: sRGB encoding (IEC 61966-2-1) of clamp(exposure × linear, 0, 1), rounded to 8 bits.
std::uint8_t encode_srgb8(double linear, double exposure);

// OpenEXR, scanline, ZIP compression, channels R, G, B, A as 32-bit FLOAT holding the image's
// values unchanged. Atomic (atomic_file.hpp); IoError when it cannot be written.
void write_exr(const std::filesystem::path& path, const Image& image);

// A PNG of 8-bit RGBA pixels as they are (e.g. a window's contents), row 0 at the top.
// Atomic; IoError when it cannot be written.
void write_png_rgba8(const std::filesystem::path& path, int width, int height, std::span<const std::uint8_t> rgba);

// 8-bit sRGB PNG with alpha: each of R, G, B through encode_srgb8(value, exposure), alpha
// round(255 × clamp(A, 0, 1)). Atomic; IoError when it cannot be written.
void write_png(const std::filesystem::path& path, const Image& image, double exposure);

}  // namespace ffcube
