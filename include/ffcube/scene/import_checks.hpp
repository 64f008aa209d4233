// ffcube's own checks of a PLY or glTF 2.0 file before assimp reads it (docs/robustness.md,
// "Third-party parsers"). Assimp 5.2.5 crashes, loops forever or reserves what a header claims
// on files that a careless exporter or a hostile upload makes; these checks read the structure
// themselves, compare every declared count and length with the bytes that are there, and throw
// InputError naming the file, the header line or JSON path, and the rule. A file that passes is
// still read by assimp in a guarded child process (assimp_loader.cpp).
#pragma once

#include <cstdint>
#include <filesystem>
#include <functional>
#include <string>
#include <string_view>

namespace ffcube {

// What the checks learned that assimp does not pass on.
struct PlyFacts {
    bool materials = false;       // an `element material`
    bool material_index = false;  // faces that pick a material by `material_index`
};

// PLY (ascii, binary_little_endian, binary_big_endian 1.0), `bytes` the whole file. Checks the
// header line by line (magic, format, element, property, comment/obj_info, a line that is
// exactly `end_header`) and then walks the data: every declared record is there, each list's
// count fits the bytes (binary) or the values on its line (ascii), and nothing but whitespace
// follows the last record.
PlyFacts check_ply(std::string_view bytes, const std::string& source);

// External files a glTF file names. `buffer` returns the bytes of a buffer's relative URI (the
// loader: a regular file in the model's folder, MappedInput) or throws InputError; `image`
// checks an image's URI (assimp records it, and does not read it) or throws.
struct GltfFiles {
    std::function<std::string_view(const std::string& uri, const std::string& where)> buffer;
    std::function<void(const std::string& uri, const std::string& where)> image;
};

struct GltfFacts {
    bool emissive_strength = false;  // KHR_materials_emissive_strength used (assimp 5.2.5 ignores it)
    std::uint64_t external_bytes = 0;  // bytes of the external buffers
};

// glTF 2.0, as JSON (.gltf) or binary (.glb: 12-byte header, JSON chunk, optional BIN chunk),
// `bytes` the whole file. Checks the container against the file size, the JSON (and its depth),
// then every buffer, bufferView, accessor (sparse included), mesh primitive (mode, attribute
// counts, every index below the vertex count, TRIANGLES a multiple of 3), node tree, and the
// indices that skins, animations, textures and materials hold, per the glTF 2.0 specification.
// `glb`: the bytes are a .glb (sniff_import_format); else JSON text.
GltfFacts check_gltf(std::string_view bytes, const std::string& source, const GltfFiles& files, bool glb);

// The file a relative URI of a model names: InputError for a scheme (file:, http:, ...), an
// absolute path, and a path that leaves `folder` (`..`, or a symlink pointing out; compared after
// weakly_canonical). The file is the URI as written (assimp 5.2.5 does not decode percent-escapes);
// the decoded spelling must stay inside the folder as well.
std::filesystem::path resolve_model_uri(const std::filesystem::path& folder, std::string_view uri,
                                        const std::string& source, const std::string& where);

// Base64 of a data: URI's payload (RFC 4648, '=' padding, no whitespace); false when invalid.
bool decode_base64(std::string_view text, std::string& out);

enum class ImportFormat { ply, gltf, glb, other };

// What assimp would take the bytes for: its PLY and glTF importers look at the content as well
// as the extension, so the checks do too ("ply\n", "glTF", or JSON under a .gltf name).
ImportFormat sniff_import_format(std::string_view head, std::string_view extension);

}  // namespace ffcube
