// Pictures of a shaded mesh on a headless GL context: rasterised into an RGBA32F framebuffer
// with a depth test, read back as floats. The values drawn are the mesh's vertex values,
// interpolated across each face (with Shading::Flat every vertex of a face holds the same value,
// and the face is drawn with that value exactly).
#pragma once

#include "ffcube/gl/context.hpp"
#include "ffcube/render/camera.hpp"
#include "ffcube/render/image.hpp"
#include "ffcube/render/shading.hpp"

namespace ffcube {

struct RenderSettings {
    int width = 512, height = 512;  // pixels, 1..16384 each
    Camera camera;
    // What a face seen from behind shows (faces are one-sided: their back neither emits nor
    // reflects): a neutral value chosen by the caller.
    Vec3 back_face_value{0.0};
    // When true each triangle shows its last (provoking) vertex's value unchanged (flat
    // interpolation: exact for a Shading::Flat mesh, whose face corners all hold the patch's
    // value); otherwise values are interpolated (perspective-correct).
    bool flat = false;
};

// Renders mesh (the near plane is 1e-6 × the distance to its farthest vertex; no far plane) with ctx, which must not
// be current on another thread; it is made current on this thread and released on return.
// Throws GlError on a GL failure, InputError for a bad size.
Image render_mesh(GlContext& ctx, const ShadedMesh& mesh, const RenderSettings& settings);

}  // namespace ffcube
