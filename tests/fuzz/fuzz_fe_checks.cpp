// libFuzzer target: ffcube's own code on the path of meshes read through Gmsh, before Gmsh sees
// the bytes (scene/gmsh_loader.hpp): the Nastran card pre-check, the .msh $PhysicalNames
// check and ffcube's legacy VTK reader (scene/vtk_legacy.hpp, its cells and a cell array), in
// process. Bad input must end in InputError; a crash, a sanitizer report, an uncaught
// InternalError or a slow input is a bug. (Gmsh itself runs in a guarded child process in
// ffcube, and is Debian's code: not fuzzed here.)
#include <cstddef>
#include <cstdint>
#include <string_view>

#include "ffcube/core/error.hpp"
#include "ffcube/scene/gmsh_loader.hpp"
#include "ffcube/scene/vtk_legacy.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    const std::string_view bytes(reinterpret_cast<const char*>(data), size);
    try {
        ffcube::check_nastran_cards(bytes, "fuzz.bdf");
    } catch (const ffcube::InputError&) {
    }
    try {
        ffcube::check_msh_physical_names(bytes, "fuzz.msh");
    } catch (const ffcube::InputError&) {
    }
    try {
        (void)ffcube::read_vtk_legacy(bytes, "fuzz.vtk", "g");
    } catch (const ffcube::InputError&) {
    }
    return 0;
}
