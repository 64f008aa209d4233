// The viewer's image files, written atomically (write_file_atomically): a reader never sees half
// a file, and a failed write leaves the previous file as it was.
#pragma once

#include <cstdint>
#include <filesystem>
#include <span>

namespace ffcube {

// 8-bit sRGB PNG (RGB: alpha is dropped). rgba: width × height pixels, 4 bytes each, the top row
// first. IoError naming the path when it cannot be written.
void write_png(const std::filesystem::path& path, int width, int height, std::span<const std::uint8_t> rgba);

// OpenEXR, half-float RGB, linear (the radiosity as it is: no exposure, no tone mapping). rgb:
// width × height pixels, 3 floats each, the top row first. IoError naming the path when it cannot
// be written.
void write_exr(const std::filesystem::path& path, int width, int height, std::span<const float> rgb);

}  // namespace ffcube
