// libFuzzer target: the CSV inputs on arbitrary bytes, through the one reader they share
// (core/csv_input.hpp): radiate's surfaces (S.csv) and bands (B.csv), the sun series (SUN.csv) and
// the albedos (A.csv). Bad input must end in InputError naming the file and line; anything else
// (a crash, a hang, another exception, a value outside its documented range) is a bug.
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <string>
#include <string_view>
#include <vector>

#include "ffcube/core/error.hpp"
#include "ffcube/solver/radiate.hpp"
#include "ffcube/solver/shortwave.hpp"

namespace {

void check(bool ok) {
    if (!ok) std::abort();
}

template <class F>
void refused_or_read(F&& f) {
    try {
        f();
    } catch (const ffcube::InputError& e) {
        // Refused with a message that names the file first (FILE:LINE: or FILE:).
        check(std::string_view(e.what()).starts_with("fuzz.csv"));
    }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    const std::string_view text(reinterpret_cast<const char*>(data), size);
    const std::string source = "fuzz.csv";
    refused_or_read([&] {
        for (const ffcube::NamedSurface& s : ffcube::parse_surfaces_csv(text, source)) {
            check(!s.object.empty());
            check(s.spec.emissivity > 0.0 && s.spec.emissivity <= 1.0 && std::isfinite(s.spec.value));
        }
    });
    refused_or_read([&] {
        for (const ffcube::NamedBand& b : ffcube::parse_bands_csv(text, source))
            check(b.lambda_min >= 0.0 && b.lambda_min < b.lambda_max && b.emissivity > 0.0 && b.emissivity <= 1.0);
    });
    refused_or_read([&] {
        for (const ffcube::SunStep& s : ffcube::parse_sun_series(text, source))
            check(std::isfinite(s.dni) && std::isfinite(s.dhi) && s.dni >= 0.0 && s.dhi >= 0.0 && !s.time.empty() &&
                  std::abs(s.x * s.x + s.y * s.y + s.z * s.z - 1.0) < 1e-9);
    });
    refused_or_read([&] {
        const std::vector<std::string> objects = {"ground", "wall", "roof"};
        for (double a : ffcube::parse_albedo_csv(text, source, objects)) check(a >= 0.0 && a < 1.0);
    });
    return 0;
}
