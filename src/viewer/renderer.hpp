// Draws the DisplayMesh with the viewer's shaders on the current context (the window's): the
// shaded patches, outlines, the ID pass for picking, and a linear float render for EXR files.
// Sets every piece of GL state it relies on (viewport, depth, culling, blending, polygon offset)
// on each call, since Dear ImGui draws with other state in between.
#pragma once

#include <glm/glm.hpp>

#include <cstdint>
#include <span>
#include <vector>

#include "ffcube/render/image.hpp"
#include "ffcube/viewer/display.hpp"
#include "gl/objects.hpp"

namespace ffcube {

enum class ToneMap { Clamp = 0, Reinhard = 1, Aces = 2 };

struct DrawSettings {
    glm::mat4 view_projection{1.0f};
    bool radiance = true;      // colours are radiosity (exposure, tone map, sRGB) or display colours
    float exposure = 0.0f;     // stops: colour × 2^exposure
    ToneMap tone_map = ToneMap::Reinhard;
    bool wireframe = false;    // every patch outline (kPatchEdge) and element edge (kElementEdge)
    std::int64_t outline = -1;  // one patch to outline brightly (the picked one), -1 for none
    bool obstructions = true;   // draw the obstruction-only surfaces (ObstructionMesh)
};

class SceneRenderer {
public:
    // Uploads the meshes; gl must be the current context's table and outlive this, and so must
    // the meshes. `obstructions` (may be empty) is drawn by draw() only: picking and the linear
    // render see through it (it has no patch index and no radiance).
    SceneRenderer(const gl::Api& gl, const DisplayMesh& mesh, const ObstructionMesh& obstructions);

    // RGB per vertex, 3 floats each (flat_colors, smooth_colors).
    void set_colors(std::span<const float> rgb);
    // Clears and draws into the bound draw framebuffer, width × height pixels. Back faces are
    // culled: an enclosure is seen from outside through the walls that face away.
    void draw(const DrawSettings& s, int width, int height);
    // 1 + the index of the patch seen at pixel (x, y) (GL convention: y = 0 the bottom row), 0 when
    // none, from an ID render of view_projection into an R32UI target.
    std::uint32_t pick(const glm::mat4& view_projection, int width, int height, int x, int y);
    // The colours as they are (no exposure, no tone map) into an RGBA32F target; alpha 1 where a
    // surface was drawn, 0 elsewhere; top row first.
    Image render_linear(const glm::mat4& view_projection, int width, int height);

private:
    void draw_triangles(const glm::mat4& view_projection, const gl::Program& program);
    void draw_obstructions(const glm::mat4& view_projection, bool outlines);

    const gl::Api& gl_;
    const DisplayMesh& mesh_;
    gl::Program scene_, id_, line_;
    gl::VertexArray vao_;
    gl::Buffer positions_, colors_, patches_, triangles_, lines_, patch_lines_, element_lines_;
    const ObstructionMesh& obstructions_;
    gl::VertexArray obstruction_vao_;
    gl::Buffer obstruction_positions_, obstruction_triangles_, obstruction_lines_;
};

// The window's back buffer as RGBA8, top row first (read before the buffers are swapped).
std::vector<std::uint8_t> read_back_buffer(const gl::Api& gl, int width, int height);

}  // namespace ffcube
