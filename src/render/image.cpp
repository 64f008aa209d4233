#include "ffcube/render/image.hpp"

#include <OpenEXR/ImfChannelList.h>
#include <OpenEXR/ImfFrameBuffer.h>
#include <OpenEXR/ImfHeader.h>
#include <OpenEXR/ImfIO.h>
#include <OpenEXR/ImfOutputFile.h>
#define STB_IMAGE_WRITE_STATIC
#define STB_IMAGE_WRITE_IMPLEMENTATION
#include <stb/stb_image_write.h>

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <numeric>
#include <ostream>
#include <string>

#include "ffcube/core/error.hpp"
#include "ffcube/io/atomic_file.hpp"

namespace ffcube {

double luminance(const Vec3& rgb) { return 0.2126 * rgb.r + 0.7152 * rgb.g + 0.0722 * rgb.b; }

double auto_exposure(std::span<const double> lum, std::span<const double> weight) {
    FFCUBE_CHECK(lum.size() == weight.size());
    std::vector<std::size_t> order(lum.size());
    std::iota(order.begin(), order.end(), std::size_t{0});
    std::sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) { return lum[a] < lum[b]; });
    const double total = std::accumulate(weight.begin(), weight.end(), 0.0);
    double seen = 0.0, median = 0.0;
    for (std::size_t k : order) {
        seen += weight[k];
        if (seen >= 0.5 * total) {
            median = lum[k];
            break;
        }
    }
    return median > 0.0 && std::isfinite(median) ? 0.3 / median : 1.0;
}

std::uint8_t encode_srgb8(double linear, double exposure) {
    double x = exposure * linear;
    x = std::isnan(x) ? 0.0 : std::clamp(x, 0.0, 1.0);
    const double s = x <= 0.0031308 ? 12.92 * x : 1.055 * std::pow(x, 1.0 / 2.4) - 0.055;
    return static_cast<std::uint8_t>(std::lround(255.0 * s));
}

namespace {

// OpenEXR writes the line offset table last and seeks back for it, and the atomic writer's stream
// cannot seek: the file is encoded into memory, then written atomically.
class MemoryOStream final : public Imf::OStream {
public:
    explicit MemoryOStream(const std::string& name) : Imf::OStream(name.c_str()) {}
    void write(const char c[], int n) override {
        const std::size_t end = pos_ + static_cast<std::size_t>(n);
        if (end > bytes_.size()) bytes_.resize(end);
        std::copy(c, c + n, bytes_.begin() + static_cast<std::ptrdiff_t>(pos_));
        pos_ = end;
    }
    uint64_t tellp() override { return pos_; }
    void seekp(uint64_t pos) override { pos_ = static_cast<std::size_t>(pos); }
    const std::string& bytes() const { return bytes_; }

private:
    std::string bytes_;
    std::size_t pos_ = 0;
};

}  // namespace

void write_exr(const std::filesystem::path& path, const Image& image) {
    FFCUBE_CHECK(image.width > 0 && image.height > 0);
    FFCUBE_CHECK(image.rgba.size() == static_cast<std::size_t>(image.width) * image.height * 4);
    MemoryOStream out(path.string());
    {
        Imf::Header header(image.width, image.height);
        header.compression() = Imf::ZIP_COMPRESSION;
        const char* names[4] = {"R", "G", "B", "A"};
        for (const char* n : names) header.channels().insert(n, Imf::Channel(Imf::FLOAT));
        Imf::FrameBuffer fb;
        const std::size_t xs = 4 * sizeof(float), ys = xs * static_cast<std::size_t>(image.width);
        for (int c = 0; c < 4; ++c)
            fb.insert(names[c], Imf::Slice(Imf::FLOAT, const_cast<char*>(reinterpret_cast<const char*>(image.rgba.data() + c)),
                                           xs, ys));
        try {
            Imf::OutputFile file(out, header);
            file.setFrameBuffer(fb);
            file.writePixels(image.height);
        } catch (const std::exception& e) {
            throw IoError(fmt::format("{}: encoding OpenEXR failed: {}", path.string(), e.what()));
        }
    }
    write_file_atomically(path, [&](std::ostream& os) {
        os.write(out.bytes().data(), static_cast<std::streamsize>(out.bytes().size()));
    });
}

void write_png_rgba8(const std::filesystem::path& path, int width, int height, std::span<const std::uint8_t> rgba) {
    FFCUBE_CHECK(width > 0 && height > 0 && rgba.size() == static_cast<std::size_t>(width) * height * 4);
    std::string encoded;
    const auto sink = [](void* context, void* data, int size) {
        static_cast<std::string*>(context)->append(static_cast<const char*>(data), static_cast<std::size_t>(size));
    };
    if (!stbi_write_png_to_func(sink, &encoded, width, height, 4, rgba.data(), width * 4))
        throw IoError(fmt::format("{}: PNG encoding failed", path.string()));
    write_file_atomically(path, [&](std::ostream& os) { os.write(encoded.data(), static_cast<std::streamsize>(encoded.size())); });
}

void write_png(const std::filesystem::path& path, const Image& image, double exposure) {
    FFCUBE_CHECK(image.width > 0 && image.height > 0);
    std::vector<std::uint8_t> px(static_cast<std::size_t>(image.width) * image.height * 4);
    for (std::size_t i = 0; i < px.size() / 4; ++i) {
        for (std::size_t c = 0; c < 3; ++c) px[4 * i + c] = encode_srgb8(image.rgba[4 * i + c], exposure);
        px[4 * i + 3] = static_cast<std::uint8_t>(std::lround(255.0 * std::clamp(double(image.rgba[4 * i + 3]), 0.0, 1.0)));
    }
    write_png_rgba8(path, image.width, image.height, px);
}

}  // namespace ffcube
