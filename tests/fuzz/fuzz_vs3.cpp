// libFuzzer target: the View3D .vs3 reader and the mesher (subdivided and --no-subdivide) on
// arbitrary bytes. Bad input must end in InputError; anything else is a bug.
#include <cstddef>
#include <cstdint>
#include <string_view>

#include "ffcube/core/error.hpp"
#include "ffcube/scene/mesher.hpp"
#include "ffcube/scene/vs3_loader.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    const std::string_view text(reinterpret_cast<const char*>(data), size);
    try {
        const ffcube::ObjModel model = ffcube::parse_vs3(text, "fuzz.vs3");
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
