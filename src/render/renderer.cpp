#include "ffcube/render/renderer.hpp"

#include <fmt/format.h>

#include <glm/gtc/matrix_transform.hpp>
#include <glm/gtc/type_ptr.hpp>

#include <algorithm>
#include <cmath>
#include <numbers>

#include "ffcube/core/error.hpp"
#include "gl/gl_api.hpp"
#include "gl/objects.hpp"
#include "gl/shaders.hpp"

namespace ffcube {
namespace {

// Releases the context on every path out of render_mesh (GL objects are destroyed first: they
// are declared after this guard).
struct CurrentGuard {
    GlContext& ctx;
    explicit CurrentGuard(GlContext& c) : ctx(c) { ctx.make_current(); }
    ~CurrentGuard() { ctx.release_current(); }
};

}  // namespace

Image render_mesh(GlContext& ctx, const ShadedMesh& mesh, const RenderSettings& s) {
    if (s.width < 1 || s.width > 16384 || s.height < 1 || s.height > 16384)
        throw InputError(fmt::format("image size {}x{}: width and height must be 1..16384 pixels", s.width, s.height));
    const Camera& cam = s.camera;
    FFCUBE_CHECK(cam.eye != cam.target);

    // Triangles with unshared vertices, relative to the eye; quads as (0,1,2) (0,2,3), so the last
    // (provoking) vertex of each triangle is a corner of its face, with the face's value when flat.
    std::vector<float> verts;
    verts.reserve(mesh.face_indices.size() * 6 * 3 / 2);
    double farthest = 0.0;  // the farthest vertex: sets the scale of the near plane
    const auto emit = [&](std::uint32_t v) {
        const Vec3 p = mesh.positions[v] - cam.eye;
        farthest = std::max(farthest, glm::length(p));
        const Vec3& c = mesh.values[v];
        for (double x : {p.x, p.y, p.z, c.r, c.g, c.b}) verts.push_back(static_cast<float>(x));
    };
    std::size_t at = 0;
    for (std::uint8_t n : mesh.face_sizes) {
        const std::uint32_t* f = &mesh.face_indices[at];
        emit(f[0]), emit(f[1]), emit(f[2]);
        if (n == 4) emit(f[0]), emit(f[2]), emit(f[3]);
        at += n;
    }
    // Reversed Z with an infinite far plane (depth = near / distance along the view axis, cleared
    // to 0, GREATER wins): with a float depth buffer the relative precision is then about 1e-7 at
    // every distance, enough to keep Cornell's light (0.1 mm below a ceiling 1.3 m away) in front
    // of the ceiling. A standard projection loses that precision with the square of the distance.
    const double near_plane = std::max(farthest * 1e-6, 1e-300);
    const double f = 1.0 / std::tan(0.5 * cam.fov_degrees * std::numbers::pi / 180.0);
    const double aspect = static_cast<double>(s.width) / s.height;
    glm::dmat4 proj(0.0);  // column-major: proj[column][row]
    proj[0][0] = f / aspect;
    proj[1][1] = f;
    proj[3][2] = near_plane;
    proj[2][3] = -1.0;
    const glm::dmat4 view = glm::lookAt(Vec3(0.0), cam.target - cam.eye, cam.up);
    const glm::mat4 vp = glm::mat4(proj * view);

    CurrentGuard current(ctx);
    const gl::Api& gl = ctx.api();
    gl::Program program = gl::make_program(gl, "shade shader", shaders::shade_vert, shaders::shade_frag);
    gl::ItemTarget target = gl::make_color_target(gl, s.width, s.height);
    gl::VertexArray vao = gl::make_vertex_array(gl);
    gl::Buffer vbo = gl::make_buffer(gl);
    gl.BindVertexArray(vao.id());
    gl.BindBuffer(GL_ARRAY_BUFFER, vbo.id());
    gl.BufferData(GL_ARRAY_BUFFER, static_cast<GLsizeiptr>(verts.size() * sizeof(float)), verts.data(), GL_STATIC_DRAW);
    gl.EnableVertexAttribArray(0);
    gl.VertexAttribPointer(0, 3, GL_FLOAT, GL_FALSE, 6 * sizeof(float), nullptr);
    gl.EnableVertexAttribArray(1);
    gl.VertexAttribPointer(1, 3, GL_FLOAT, GL_FALSE, 6 * sizeof(float), reinterpret_cast<const void*>(3 * sizeof(float)));

    // Every state this pass depends on is set here, none assumed.
    gl.BindFramebuffer(GL_FRAMEBUFFER, target.fbo.id());
    gl.Viewport(0, 0, s.width, s.height);
    gl.Disable(GL_BLEND);
    gl.Disable(GL_CULL_FACE);
    gl.Disable(GL_SCISSOR_TEST);
    gl.Disable(GL_FRAMEBUFFER_SRGB);
    gl.Disable(GL_MULTISAMPLE);
    gl.Disable(GL_DITHER);
    gl.Enable(GL_DEPTH_TEST);
    gl.DepthFunc(GL_GREATER);
    gl.DepthMask(GL_TRUE);
    gl.ColorMask(GL_TRUE, GL_TRUE, GL_TRUE, GL_TRUE);
    gl.ClipControl(GL_LOWER_LEFT, GL_ZERO_TO_ONE);
    const float clear_color[4] = {0, 0, 0, 0};
    const float clear_depth = 0.0f;
    gl.ClearBufferfv(GL_COLOR, 0, clear_color);
    gl.ClearBufferfv(GL_DEPTH, 0, &clear_depth);

    gl.UseProgram(program.id());
    gl.UniformMatrix4fv(gl.GetUniformLocation(program.id(), "u_view_projection"), 1, GL_FALSE, glm::value_ptr(vp));
    gl.Uniform1i(gl.GetUniformLocation(program.id(), "u_flat"), s.flat ? 1 : 0);
    gl.Uniform3f(gl.GetUniformLocation(program.id(), "u_back"), static_cast<float>(s.back_face_value.r),
                 static_cast<float>(s.back_face_value.g), static_cast<float>(s.back_face_value.b));
    gl.DrawArrays(GL_TRIANGLES, 0, static_cast<GLsizei>(verts.size() / 6));

    Image image;
    image.width = s.width;
    image.height = s.height;
    image.rgba.resize(static_cast<std::size_t>(s.width) * s.height * 4);
    std::vector<float> rows(image.rgba.size());
    gl.PixelStorei(GL_PACK_ALIGNMENT, 4);
    gl.ReadPixels(0, 0, s.width, s.height, GL_RGBA, GL_FLOAT, rows.data());
    gl::check_gl(gl, "rendering the picture");
    // GL's row 0 is the bottom; the image's is the top.
    const std::size_t stride = static_cast<std::size_t>(s.width) * 4;
    for (int y = 0; y < s.height; ++y)
        std::copy_n(rows.begin() + static_cast<std::ptrdiff_t>(stride * (s.height - 1 - y)), stride,
                    image.rgba.begin() + static_cast<std::ptrdiff_t>(stride * y));
    gl.UseProgram(0);
    gl.BindVertexArray(0);
    gl.BindFramebuffer(GL_FRAMEBUFFER, 0);
    return image;
}

}  // namespace ffcube
