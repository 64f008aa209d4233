// Internal to the io layer: what the .ffm versions 1 and 2 share (the 64-byte header, the text
// block, the head's validation). Layouts in docs/ffm-format.md.
#pragma once

#include <fmt/format.h>

#include <array>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <limits>
#include <string>
#include <vector>

#include "ffcube/core/error.hpp"
#include "ffcube/core/le_bytes.hpp"
#include "ffcube/io/ffm.hpp"
#include "ffcube/scene/scene.hpp"

namespace ffcube::ffm_detail {

constexpr std::array<char, 8> kMagic = {'F', 'F', 'C', 'U', 'B', 'E', 'F', 'M'};
constexpr std::size_t kHeaderSize = 64;
// Values above 1 can only come from float rounding of row entries near 1; anything beyond this
// slack is not a form factor.
constexpr float kMaxValue = 1.0f + 1e-3f;

constexpr std::uint64_t pad8(std::uint64_t bytes) { return (bytes + 7) / 8 * 8; }

// File size implied by the header, in 128 bits: a corrupted nnz near 2^64 must not wrap around
// to a plausible size.
__extension__ using u128 = unsigned __int128;

struct Header {
    std::uint32_t version = 0, n = 0, object_count = 0, resolution = 0;
    // Version 1: the number of entries. Version 2: u32 block_bytes (the writer's block size,
    // bounds a block's coded size) then u32 0; the entry count is in the trailer.
    std::uint64_t nnz = 0, fingerprint = 0;
    double max_patch_edge = 0.0;
    std::uint32_t method_len = 0, meshing_len = 0, settings_len = 0, names_len = 0;

    std::uint64_t text_bytes() const {
        return pad8(std::uint64_t(method_len) + meshing_len + settings_len + names_len);
    }
    u128 file_size() const {
        return u128(kHeaderSize) + text_bytes() + u128(8) * n + u128(8) * (u128(n) + 1) + pad8(4 * std::uint64_t(n)) +
               2 * ((u128(4) * nnz + 7) / 8 * 8) + 8;
    }
};

inline std::array<unsigned char, kHeaderSize> encode(const Header& h) {
    std::array<unsigned char, kHeaderSize> b{};
    std::memcpy(b.data(), kMagic.data(), kMagic.size());
    store_le(b.data() + 8, h.version);
    store_le(b.data() + 12, h.n);
    store_le(b.data() + 16, h.object_count);
    store_le(b.data() + 20, h.resolution);
    store_le(b.data() + 24, h.nnz);
    store_le(b.data() + 32, h.fingerprint);
    store_le(b.data() + 40, h.max_patch_edge);
    store_le(b.data() + 48, h.method_len);
    store_le(b.data() + 52, h.meshing_len);
    store_le(b.data() + 56, h.settings_len);
    store_le(b.data() + 60, h.names_len);
    return b;
}

inline Header decode(const unsigned char* b) {
    Header h;
    h.version = load_le<std::uint32_t>(b + 8);
    h.n = load_le<std::uint32_t>(b + 12);
    h.object_count = load_le<std::uint32_t>(b + 16);
    h.resolution = load_le<std::uint32_t>(b + 20);
    h.nnz = load_le<std::uint64_t>(b + 24);
    h.fingerprint = load_le<std::uint64_t>(b + 32);
    h.max_patch_edge = load_le<double>(b + 40);
    h.method_len = load_le<std::uint32_t>(b + 48);
    h.meshing_len = load_le<std::uint32_t>(b + 52);
    h.settings_len = load_le<std::uint32_t>(b + 56);
    h.names_len = load_le<std::uint32_t>(b + 60);
    return h;
}

inline std::uint32_t checked_u32(std::size_t v, const char* what) {
    FFCUBE_CHECK_MSG(v <= std::numeric_limits<std::uint32_t>::max(), fmt::format("{} does not fit in 32 bits", what));
    return static_cast<std::uint32_t>(v);
}


// The header fields that describe the scene and the metadata (version and nnz left to the caller),
// and the text block (method, meshing, settings, object names), zero-padded to 8 bytes.
Header scene_header(const Scene& scene, const FfmMetadata& meta);
std::vector<unsigned char> text_block(const Scene& scene, const FfmMetadata& meta, const Header& h);
// The scene's patch areas and objects, checked as the reader checks them (InternalError).
void scene_arrays(const Scene& scene, std::vector<double>& areas, std::vector<std::uint32_t>& objects);

// Fills f's metadata, meshing and object names from the text block (text_bytes() bytes) and
// checks max_patch_edge, the areas and objects already in f: throws InputError "NAME: invalid:
// ..." for the first rule broken.
void parse_head(const std::string& text, const Header& h, FfmHead& f);

// read_ffm for a file whose header says version 2.
FfmFile read_ffm_v2(const std::filesystem::path& path);

inline InputError invalid(const std::string& name, const std::string& what) {
    return InputError(fmt::format("{}: invalid: {}", name, what));
}

}  // namespace ffcube::ffm_detail
