// Sunlit fractions by an orthographic item buffer along the sun direction (docs/urban.md, "Sun
// and shade"). Every patch of the drawn scene (obstructions included) is rasterized with its own
// ID, front and back faces alike (a back face blocks), on a pixel grid in the plane ⟂ to the sun;
// a patch's sunlit projected area is its pixel count × the pixel's area. No GL type here.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "ffcube/gl/context.hpp"
#include "ffcube/scene/scene.hpp"

namespace ffcube {

struct SunOptions {
    // The error wanted on the sunlit share of the worst-resolved lit patch, as the worst-case bound
    // perimeter × pixel / projected area (sun_buffer.cpp); in (0, 1).
    double tolerance = 1e-3;
    // At most this many pixels in all tiles together (the pixel is made larger, and the bound
    // reported, when the tolerance would need more). ≥ 1.
    std::uint64_t max_pixels = std::uint64_t{1} << 27;
    // Side of one framebuffer tile in pixels; 0: min(4096, GL_MAX_TEXTURE_SIZE,
    // GL_MAX_RENDERBUFFER_SIZE, GL_MAX_VIEWPORT_DIMS). Smaller values are for tests of tiling.
    int tile = 0;
    Backend backend = Backend::Auto;
};

struct SunResult {
    Vec3 sun{0.0};                           // the unit direction towards the sun
    std::vector<double> fraction;            // per patch of the scene (not its obstructions): in [0, 1]
    std::vector<double> cosine;              // n·s (≤ 1e-9: facing away or edge-on, fraction 0)
    std::vector<std::uint64_t> pixels;       // pixels showing the patch
    double pixel_size = 0.0;                 // scene units (square pixels)
    double wanted_pixel_size = 0.0;          // what the tolerance asked for (before the pixel budget)
    std::uint64_t pixels_u = 0, pixels_v = 0;  // the grid over the projected bounding box
    int tile_size = 0, tiles_u = 0, tiles_v = 0;
    std::size_t lit_patches = 0;             // n·s > 1e-9
    std::size_t clamped = 0;                 // lit patches whose measured share exceeded 1 (set to 1)
    double max_overshoot = 0.0;              // the largest share − 1 before clamping
    double error_bound = 0.0;                // max over lit patches of perimeter × pixel / projected area
    std::size_t under_resolved = 0;          // lit patches whose bound exceeds the tolerance
    double sunlit_projected_area = 0.0;      // Σ pixels × pixel area over the scene's patches
    double seconds = 0.0;                    // the whole computation (context, drawing, counting)
    // Its parts: GL objects made (program, framebuffer), the tiles' vertices projected and uploaded,
    // the GL's rasterization (to glFinish), the read-back of the IDs, and counting them.
    double seconds_setup = 0.0, seconds_project = 0.0, seconds_draw = 0.0, seconds_readback = 0.0, seconds_count = 0.0;
    std::string renderer;                    // GL_RENDERER
};

// The unit direction towards a sun at azimuth `azimuth_deg` (clockwise from north, +y; east = 90°,
// +x) and elevation `elevation_deg` above the horizon (+z up; 90: the zenith). InputError naming
// --sun when either is not finite or the elevation is outside [-90, 90].
Vec3 sun_direction_from_angles(double azimuth_deg, double elevation_deg);

// InputError (naming `option`) for a zero or non-finite direction; the unit vector otherwise.
Vec3 normalized_sun_direction(Vec3 towards_sun, const char* option = "--sun-direction");

// Sunlit fractions of every patch of `scene` for the sun in direction `towards_sun` (need not be
// unit; InputError when zero or not finite). Makes its own headless context (GlError when none
// can be made). Deterministic: the same scene and options give the same result.
SunResult sunlit_fractions(const Scene& scene, Vec3 towards_sun, const SunOptions& options = {});
// The same in a context the caller made once (create_headless_context) for many sun positions:
// made current for the call and released after it. The result is the same as above. Make and
// destroy no other context while it is lent: that can end the EGL display they share.
SunResult sunlit_fractions(const Scene& scene, Vec3 towards_sun, const SunOptions& options, GlContext& context);
// nullptr: a context of its own (the first form).
SunResult sunlit_fractions(const Scene& scene, Vec3 towards_sun, const SunOptions& options, GlContext* context);

// The same fractions without pixels and without GL: every shadow cast on a patch's plane is
// clipped as a polygon and subtracted from the patch's projection (sun_clip.cpp), so each
// fraction is exact up to rounding (no tolerance, no pixel budget; pixel fields stay 0,
// error_bound 0). `threads` 0: the hardware's; the result does not depend on it. InputError for a
// zero or non-finite direction.
SunResult sunlit_fractions_clipped(const Scene& scene, Vec3 towards_sun, unsigned threads = 0);

}  // namespace ffcube
