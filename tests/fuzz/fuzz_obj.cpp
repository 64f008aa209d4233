// libFuzzer target: the OBJ/MTL loader and the mesher on arbitrary bytes.
// Input: OBJ text, optionally followed by "\n#MTL\n" and the text every 'mtllib' resolves to.
// The input's length modulo 4 chooses the ObjObjectsBy mode (auto, o, g, material).
// Bad input must end in InputError; anything else (a crash, a sanitizer report, an uncaught
// InternalError = a failed FFCUBE_CHECK) is a bug.
#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>
#include <string_view>

#include "ffcube/core/error.hpp"
#include "ffcube/scene/mesher.hpp"
#include "ffcube/scene/obj_loader.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    const std::string_view all(reinterpret_cast<const char*>(data), size);
    constexpr std::string_view kSeparator = "\n#MTL\n";
    const std::size_t cut = all.find(kSeparator);
    const std::string_view obj = all.substr(0, cut);
    const std::string mtl = cut == std::string_view::npos ? std::string() : std::string(all.substr(cut + kSeparator.size()));
    const ffcube::MtlResolver resolver = [&](const std::string&) -> std::optional<std::string> {
        if (cut == std::string_view::npos) return std::nullopt;
        return mtl;
    };
    try {
        // Every way of naming objects (--objects-by), chosen by the input's length.
        constexpr ffcube::ObjObjectsBy kBy[] = {ffcube::ObjObjectsBy::automatic, ffcube::ObjObjectsBy::o,
                                                ffcube::ObjObjectsBy::g, ffcube::ObjObjectsBy::material};
        const ffcube::ObjModel model = ffcube::parse_obj(obj, "fuzz.obj", resolver, {kBy[size % 4]});
        // Mesh it too, small: a fuzzed scene must not make the mesher misbehave either. The
        // patch limit keeps a tiny edge on a huge face from running out of memory on purpose.
        ffcube::MeshOptions options;
        options.target_patches = 64;
        options.max_patches = 4096;
        (void)ffcube::build_scene(model, options);
    } catch (const ffcube::InputError&) {
        // refused with a message: the expected outcome for bad input
    }
    return 0;
}
