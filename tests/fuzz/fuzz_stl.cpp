// libFuzzer target: the STL reader (ASCII and binary) and the mesher on arbitrary bytes.
// Bad input must end in InputError; anything else (a crash, a sanitizer report, an uncaught
// InternalError = a failed FFCUBE_CHECK) is a bug.
#include <cstddef>
#include <cstdint>
#include <string_view>

#include "ffcube/core/error.hpp"
#include "ffcube/scene/mesher.hpp"
#include "ffcube/scene/stl_loader.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    const std::string_view bytes(reinterpret_cast<const char*>(data), size);
    try {
        const ffcube::ObjModel model = ffcube::parse_stl(bytes, "fuzz.stl", "fuzz");
        ffcube::MeshOptions options;
        options.target_patches = 64;
        options.max_patches = 4096;
        (void)ffcube::build_scene(model, options);
        ffcube::MeshOptions one;
        one.subdivide = false;
        (void)ffcube::build_scene(model, one);
    } catch (const ffcube::InputError&) {
        // refused with a message: the expected outcome for bad input
    }
    return 0;
}
