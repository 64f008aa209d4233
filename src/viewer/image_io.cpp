#include "ffcube/viewer/image_io.hpp"

#include <OpenEXR/ImfRgbaFile.h>
#include <OpenEXR/ImfStdIO.h>
#include <fmt/format.h>
#include <stb/stb_image_write.h>

#include <ostream>
#include <string>
#include <vector>

#include "ffcube/core/error.hpp"
#include "ffcube/io/atomic_file.hpp"

namespace ffcube {

void write_png(const std::filesystem::path& path, int width, int height, std::span<const std::uint8_t> rgba) {
    FFCUBE_CHECK_MSG(width > 0 && height > 0 && rgba.size() == 4ull * width * height, "one RGBA pixel per position");
    std::vector<std::uint8_t> rgb(3ull * width * height);
    for (std::size_t i = 0; i < rgb.size() / 3; ++i)
        for (int c = 0; c < 3; ++c) rgb[3 * i + c] = rgba[4 * i + c];
    write_file_atomically(path, [&](std::ostream& out) {
        const auto sink = [](void* context, void* data, int size) {
            static_cast<std::ostream*>(context)->write(static_cast<const char*>(data), size);
        };
        if (!stbi_write_png_to_func(sink, &out, width, height, 3, rgb.data(), 3 * width))
            throw IoError(fmt::format("{}: PNG encoding failed", path.string()));
    });
}

void write_exr(const std::filesystem::path& path, int width, int height, std::span<const float> rgb) {
    FFCUBE_CHECK_MSG(width > 0 && height > 0 && rgb.size() == 3ull * width * height, "one RGB pixel per position");
    std::vector<Imf::Rgba> pixels(static_cast<std::size_t>(width) * height);
    for (std::size_t i = 0; i < pixels.size(); ++i) pixels[i] = Imf::Rgba(rgb[3 * i], rgb[3 * i + 1], rgb[3 * i + 2], 1.0f);
    // Encoded in memory, then written through the atomic writer (OpenEXR would otherwise write
    // the destination in place).
    Imf::StdOSStream encoded;
    try {
        Imf::RgbaOutputFile file(encoded, Imf::Header(width, height), Imf::WRITE_RGB);
        file.setFrameBuffer(pixels.data(), 1, static_cast<std::size_t>(width));
        file.writePixels(height);
    } catch (const std::exception& e) {
        throw IoError(fmt::format("{}: EXR encoding failed: {}", path.string(), e.what()));
    }
    const std::string bytes = encoded.str();
    write_file_atomically(path, [&](std::ostream& out) { out.write(bytes.data(), static_cast<std::streamsize>(bytes.size())); });
}

}  // namespace ffcube
