// View factors from every patch of a scene to the patches of a subdivided sky (docs/urban.md,
// "A day of shortwave"): V_ip = (1/π) ∫ over sky patch p, unobstructed from patch i, of cos θ dω.
// The Tregenza sky (Tregenza 1987; CIE 2003): 145 patches in 8 bands of altitude, 12° high
// (30, 30, 24, 24, 18, 12, 6 patches, and the zenith cap above 84°). Only the upper hemisphere
// (altitude ≥ 0) is sky. Directions follow gl/sun.hpp: +z up, azimuth clockwise from north (+y).
#pragma once

#include <cstdint>
#include <vector>

#include "ffcube/scene/scene.hpp"

namespace ffcube {

struct SkyPatch {
    double alt0 = 0, alt1 = 0;  // altitude range, radians, alt0 < alt1
    double az0 = 0, az1 = 0;    // azimuth range, radians, clockwise from north, az0 < az1
};

// The 145 Tregenza patches, band by band from the horizon up, each band from north clockwise
// (the first patch of a band is centred on north).
std::vector<SkyPatch> tregenza_patches();

struct SkyPatchOptions {
    // Each sky patch is cut into cells × cells; a cell the patch's horizon plane crosses is cut
    // further (up to `horizon_depth` halvings), and each leaf cell's visibility is traced.
    std::uint32_t cells = 2;
    std::uint32_t horizon_depth = 4;
    unsigned threads = 0;  // 0: hardware concurrency
};

struct SkyPatchViewFactors {
    std::uint32_t patches = 0;   // scene patches
    std::uint32_t sky = 0;       // sky patches
    std::vector<double> v;       // v[i * sky + p]
    std::uint64_t rays = 0;
    double seconds = 0.0;
};

// Per scene patch i and sky patch p: V_ip. The cosine integral over each leaf cell is exact
// (∫ d dω over an altitude–azimuth cell is closed form and n·d is linear in d); a cell counts as
// open in the share of the patch's sample points (3 per triangle) from which a ray along the cell's
// mean direction meets nothing of the drawn scene (obstructions included). An unobstructed
// horizontal patch gets exactly the analytic values (1/2π) Δaz (sin² alt1 − sin² alt0), summing
// to 1. Deterministic whatever the thread count.
SkyPatchViewFactors sky_patch_view_factors(const Scene& scene, const std::vector<SkyPatch>& sky,
                                           const SkyPatchOptions& options = {});

}  // namespace ffcube
