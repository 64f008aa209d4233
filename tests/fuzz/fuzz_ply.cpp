// libFuzzer target: what ffcube runs on a PLY file before assimp sees it (the format sniffing and
// check_ply, scene/import_checks.hpp), in process. Bad input must end in InputError; a crash, a
// sanitizer report, an uncaught InternalError or a slow input is a bug. (assimp itself runs in a
// guarded child process in ffcube, and is Debian's code: not fuzzed here.)
#include <cstddef>
#include <cstdint>
#include <string>
#include <string_view>

#include "ffcube/core/error.hpp"
#include "ffcube/scene/import_checks.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    const std::string_view bytes(reinterpret_cast<const char*>(data), size);
    try {
        // The loader checks as PLY what starts with "ply" or is named .ply: both reach check_ply.
        if (ffcube::sniff_import_format(bytes.substr(0, 4096), ".ply") != ffcube::ImportFormat::ply) return 0;
        const ffcube::PlyFacts facts = ffcube::check_ply(bytes, "fuzz.ply");
        (void)facts;
    } catch (const ffcube::InputError&) {
        // refused with a message: the expected outcome for bad input
    }
    return 0;
}
