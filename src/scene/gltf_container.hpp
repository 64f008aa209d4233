// The outer layer of a glTF file (gltf_check.cpp reads the JSON inside): a .glb's header and
// chunks checked against the file size before anything is reserved.
#pragma once

#include <optional>
#include <string>
#include <string_view>

namespace ffcube::detail {

struct GltfContainer {
    std::string_view json;
    std::optional<std::string_view> bin;  // a .glb's BIN chunk, when present
};

// A .glb (magic "glTF", version 2, length == the file's size, a JSON chunk first, a BIN chunk
// optional, every chunk within the file), or the bytes as JSON text.
GltfContainer split_gltf(std::string_view bytes, bool glb, const std::string& source);

}  // namespace ffcube::detail
