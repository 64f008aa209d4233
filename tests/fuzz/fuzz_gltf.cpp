// libFuzzer target: what ffcube runs on a glTF 2.0 file (.gltf JSON or .glb) before assimp sees
// it: the format sniffing, the GLB container, the JSON and every buffer, view, accessor, index,
// node and reference check (check_gltf, scene/import_checks.hpp), and the URI rules
// (resolve_model_uri, against a folder that does not exist). An external buffer's bytes are the
// input's text after a "\n#BIN\n" separator. Bad input must end in InputError; a crash, a
// sanitizer report, an uncaught InternalError or a slow input is a bug.
#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <string>
#include <string_view>

#include "ffcube/core/error.hpp"
#include "ffcube/scene/import_checks.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    const std::string_view input(reinterpret_cast<const char*>(data), size);
    const std::size_t cut = input.find("\n#BIN\n");
    const std::string_view bytes = input.substr(0, cut);
    const std::string_view external = cut == std::string_view::npos ? std::string_view() : input.substr(cut + 6);
    const std::string source = "fuzz.gltf";
    const std::filesystem::path folder = "/nonexistent-ffcube-fuzz/model";
    ffcube::GltfFiles files;
    files.buffer = [&](const std::string& uri, const std::string& where) {
        (void)ffcube::resolve_model_uri(folder, uri, source, where);
        return external;
    };
    files.image = [&](const std::string& uri, const std::string& where) { (void)ffcube::resolve_model_uri(folder, uri, source, where); };
    try {
        // The loader takes the bytes for a .glb when they begin with "glTF", else as JSON.
        const ffcube::ImportFormat format = ffcube::sniff_import_format(bytes.substr(0, 4096), ".gltf");
        (void)ffcube::check_gltf(bytes, source, files, format == ffcube::ImportFormat::glb);
    } catch (const ffcube::InputError&) {
        // refused with a message: the expected outcome for bad input
    }
    return 0;
}
