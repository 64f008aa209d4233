// ffcube sun --sun-series: absorbed shortwave per patch (or object) and step, with reflections
// solved on F (solver/shortwave.hpp; docs/urban.md, "A day of shortwave").
#pragma once

#include <string>

#include "cli/common.hpp"
#include "ffcube/gl/sun.hpp"

namespace ffcube::cli {

struct SunSeriesRequest {
    SceneFlags scene;
    std::string series, albedo, matrix, sky_patches = "isotropic", sky_out, out, by = "patch", report;
    SunOptions sun;         // the item buffer of every step (backend resolved)
    double tolerance = 1e-12;  // the reflections' stopping rule (ShortwaveControl::tolerance)
    std::uint32_t batch = 32;  // steps computed, solved and written together
    std::string method = "clip";  // the direct beam: clip (sunlit_fractions_clipped) or pixels (the item buffer)
};

int run_sun_series(const SunSeriesRequest& request);

}  // namespace ffcube::cli
