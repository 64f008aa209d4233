#include "renderer.hpp"

#include <glm/gtc/type_ptr.hpp>

#include "ffcube/core/error.hpp"
#include "gl/shaders.hpp"

namespace ffcube {
namespace {

template <typename T>
gl::Buffer make_static_buffer(const gl::Api& gl, GLenum target, std::span<const T> data) {
    gl::Buffer b = gl::make_buffer(gl);
    gl.BindBuffer(target, b.id());
    gl.BufferData(target, static_cast<GLsizeiptr>(data.size_bytes()), data.data(), GL_STATIC_DRAW);
    return b;
}

void flip_rows(std::span<std::uint8_t> pixels, std::size_t row_bytes, int height);

}  // namespace

SceneRenderer::SceneRenderer(const gl::Api& gl, const DisplayMesh& mesh, const ObstructionMesh& obstructions)
    : gl_(gl),
      mesh_(mesh),
      scene_(gl::make_program(gl, "view_scene", shaders::view_scene_vert, shaders::view_scene_frag)),
      id_(gl::make_program(gl, "view_id", shaders::view_scene_vert, shaders::view_id_frag)),
      line_(gl::make_program(gl, "view_line", shaders::view_scene_vert, shaders::view_line_frag)),
      vao_(gl::make_vertex_array(gl)),
      obstructions_(obstructions),
      obstruction_vao_(gl::make_vertex_array(gl)) {
    gl.BindVertexArray(vao_.id());
    positions_ = make_static_buffer(gl, GL_ARRAY_BUFFER, std::span<const float>(mesh.positions));
    gl.EnableVertexAttribArray(0);
    gl.VertexAttribPointer(0, 3, GL_FLOAT, GL_FALSE, 0, nullptr);
    colors_ = gl::make_buffer(gl);
    gl.BindBuffer(GL_ARRAY_BUFFER, colors_.id());
    gl.BufferData(GL_ARRAY_BUFFER, static_cast<GLsizeiptr>(3 * sizeof(float) * mesh.vertex_count()), nullptr, GL_DYNAMIC_DRAW);
    gl.EnableVertexAttribArray(1);
    gl.VertexAttribPointer(1, 3, GL_FLOAT, GL_FALSE, 0, nullptr);
    patches_ = make_static_buffer(gl, GL_ARRAY_BUFFER, std::span<const std::uint32_t>(mesh.patch));
    gl.EnableVertexAttribArray(2);
    gl.VertexAttribIPointer(2, 1, GL_UNSIGNED_INT, 0, nullptr);
    triangles_ = make_static_buffer(gl, GL_ELEMENT_ARRAY_BUFFER, std::span<const std::uint32_t>(mesh.triangles));
    lines_ = make_static_buffer(gl, GL_ARRAY_BUFFER, std::span<const std::uint32_t>(mesh.lines));
    patch_lines_ = make_static_buffer(gl, GL_ARRAY_BUFFER, std::span<const std::uint32_t>(mesh.patch_lines));
    element_lines_ = make_static_buffer(gl, GL_ARRAY_BUFFER, std::span<const std::uint32_t>(mesh.element_lines));
    gl.BindVertexArray(obstruction_vao_.id());
    obstruction_positions_ = make_static_buffer(gl, GL_ARRAY_BUFFER, std::span<const float>(obstructions.positions));
    gl.EnableVertexAttribArray(0);
    gl.VertexAttribPointer(0, 3, GL_FLOAT, GL_FALSE, 0, nullptr);
    obstruction_triangles_ = make_static_buffer(gl, GL_ELEMENT_ARRAY_BUFFER, std::span<const std::uint32_t>(obstructions.triangles));
    obstruction_lines_ = make_static_buffer(gl, GL_ARRAY_BUFFER, std::span<const std::uint32_t>(obstructions.lines));
    gl.BindVertexArray(0);
    gl.BindBuffer(GL_ARRAY_BUFFER, 0);
    gl::check_gl(gl, "uploading the viewer's mesh");
}

void SceneRenderer::set_colors(std::span<const float> rgb) {
    FFCUBE_CHECK_MSG(rgb.size() == 3 * mesh_.vertex_count(), "one RGB colour per vertex");
    gl_.BindBuffer(GL_ARRAY_BUFFER, colors_.id());
    gl_.BufferSubData(GL_ARRAY_BUFFER, 0, static_cast<GLsizeiptr>(rgb.size_bytes()), rgb.data());
    gl_.BindBuffer(GL_ARRAY_BUFFER, 0);
}

void SceneRenderer::draw_triangles(const glm::mat4& view_projection, const gl::Program& program) {
    gl_.UseProgram(program.id());
    gl_.UniformMatrix4fv(gl_.GetUniformLocation(program.id(), "u_view_proj"), 1, GL_FALSE, glm::value_ptr(view_projection));
    gl_.BindVertexArray(vao_.id());
    gl_.BindBuffer(GL_ELEMENT_ARRAY_BUFFER, triangles_.id());
    gl_.DrawElements(GL_TRIANGLES, static_cast<GLsizei>(mesh_.triangles.size()), GL_UNSIGNED_INT, nullptr);
}

namespace {

// State both passes need, whatever ImGui left behind.
void prepare(const gl::Api& gl, int width, int height) {
    gl.Viewport(0, 0, width, height);
    gl.Disable(GL_SCISSOR_TEST);
    gl.Disable(GL_BLEND);
    gl.Enable(GL_DEPTH_TEST);
    gl.DepthFunc(GL_LEQUAL);
    gl.DepthMask(GL_TRUE);
    gl.ColorMask(GL_TRUE, GL_TRUE, GL_TRUE, GL_TRUE);
    gl.Enable(GL_CULL_FACE);
    gl.CullFace(GL_BACK);
    gl.FrontFace(GL_CCW);
    gl.PolygonMode(GL_FRONT_AND_BACK, GL_FILL);
}

}  // namespace

// Translucent glass over what is already drawn: no depth writes (what lies behind stays visible
// through a second layer too), both sides; with the wireframe, the patch outlines opaque.
void SceneRenderer::draw_obstructions(const glm::mat4& view_projection, bool outlines) {
    if (obstructions_.triangles.empty()) return;
    gl_.UseProgram(line_.id());
    gl_.UniformMatrix4fv(gl_.GetUniformLocation(line_.id(), "u_view_proj"), 1, GL_FALSE, glm::value_ptr(view_projection));
    const GLint color = gl_.GetUniformLocation(line_.id(), "u_color");
    const GLint alpha = gl_.GetUniformLocation(line_.id(), "u_alpha");
    gl_.Uniform3f(color, static_cast<float>(kObstruction.r), static_cast<float>(kObstruction.g), static_cast<float>(kObstruction.b));
    gl_.BindVertexArray(obstruction_vao_.id());
    gl_.Disable(GL_CULL_FACE);
    gl_.Enable(GL_BLEND);
    gl_.BlendFunc(GL_SRC_ALPHA, GL_ONE_MINUS_SRC_ALPHA);
    gl_.DepthMask(GL_FALSE);
    gl_.Uniform1f(alpha, kObstructionAlpha);
    gl_.BindBuffer(GL_ELEMENT_ARRAY_BUFFER, obstruction_triangles_.id());
    gl_.DrawElements(GL_TRIANGLES, static_cast<GLsizei>(obstructions_.triangles.size()), GL_UNSIGNED_INT, nullptr);
    gl_.Disable(GL_BLEND);
    gl_.DepthMask(GL_TRUE);
    gl_.Uniform1f(alpha, 1.0f);
    if (outlines) {
        gl_.BindBuffer(GL_ELEMENT_ARRAY_BUFFER, obstruction_lines_.id());
        gl_.DrawElements(GL_LINES, static_cast<GLsizei>(obstructions_.lines.size()), GL_UNSIGNED_INT, nullptr);
    }
    gl_.Enable(GL_CULL_FACE);
}

void SceneRenderer::draw(const DrawSettings& s, int width, int height) {
    prepare(gl_, width, height);
    const float background[4] = {0.08f, 0.08f, 0.09f, 1.0f};
    const float far_depth = 1.0f;
    gl_.ClearBufferfv(GL_COLOR, 0, background);
    gl_.ClearBufferfv(GL_DEPTH, 0, &far_depth);

    // Surfaces pushed back a little so that outlines at the same depth win the depth test.
    gl_.Enable(GL_POLYGON_OFFSET_FILL);
    gl_.PolygonOffset(1.0f, 1.0f);
    gl_.UseProgram(scene_.id());
    gl_.Uniform1i(gl_.GetUniformLocation(scene_.id(), "u_mode"), s.radiance ? 0 : 1);
    gl_.Uniform1f(gl_.GetUniformLocation(scene_.id(), "u_exposure"), s.exposure);
    gl_.Uniform1i(gl_.GetUniformLocation(scene_.id(), "u_tone_map"), static_cast<int>(s.tone_map));
    draw_triangles(s.view_projection, scene_);
    gl_.Disable(GL_POLYGON_OFFSET_FILL);
    if (s.obstructions) draw_obstructions(s.view_projection, s.wireframe);

    if (s.wireframe || s.outline >= 0) {
        gl_.UseProgram(line_.id());
        gl_.UniformMatrix4fv(gl_.GetUniformLocation(line_.id(), "u_view_proj"), 1, GL_FALSE, glm::value_ptr(s.view_projection));
        gl_.BindVertexArray(vao_.id());
        const GLint color = gl_.GetUniformLocation(line_.id(), "u_color");
        if (s.wireframe) {
            // Element edges first, patch outlines over them where they meet.
            const auto draw_lines = [&](const gl::Buffer& buffer, std::size_t count, const Vec3& c) {
                if (count == 0) return;
                gl_.BindBuffer(GL_ELEMENT_ARRAY_BUFFER, buffer.id());
                gl_.Uniform3f(color, static_cast<float>(c.r), static_cast<float>(c.g), static_cast<float>(c.b));
                gl_.DrawElements(GL_LINES, static_cast<GLsizei>(count), GL_UNSIGNED_INT, nullptr);
            };
            draw_lines(element_lines_, mesh_.element_lines.size(), kElementEdge);
            draw_lines(patch_lines_, mesh_.patch_lines.size(), kPatchEdge);
        }
        gl_.BindBuffer(GL_ELEMENT_ARRAY_BUFFER, lines_.id());
        if (s.outline >= 0) {
            const auto p = static_cast<std::size_t>(s.outline);
            gl_.Uniform3f(color, 1.0f, 1.0f, 1.0f);
            gl_.Disable(GL_DEPTH_TEST);  // the picked patch stays visible behind other surfaces
            gl_.DrawElements(GL_LINES, static_cast<GLsizei>(mesh_.first_line[p + 1] - mesh_.first_line[p]), GL_UNSIGNED_INT,
                             reinterpret_cast<const void*>(sizeof(std::uint32_t) * mesh_.first_line[p]));
        }
    }
    gl_.BindVertexArray(0);
    gl_.UseProgram(0);
    gl::check_gl(gl_, "drawing the scene");
}

std::uint32_t SceneRenderer::pick(const glm::mat4& view_projection, int width, int height, int x, int y) {
    if (x < 0 || y < 0 || x >= width || y >= height) return 0;
    gl::ItemTarget target = gl::make_item_target(gl_, width, height);  // leaves its framebuffer bound
    prepare(gl_, width, height);
    const GLuint nothing[4] = {0, 0, 0, 0};
    const float far_depth = 1.0f;
    gl_.ClearBufferuiv(GL_COLOR, 0, nothing);
    gl_.ClearBufferfv(GL_DEPTH, 0, &far_depth);
    draw_triangles(view_projection, id_);
    std::uint32_t item = 0;
    gl_.PixelStorei(GL_PACK_ALIGNMENT, 4);
    gl_.ReadPixels(x, y, 1, 1, GL_RED_INTEGER, GL_UNSIGNED_INT, &item);
    gl_.BindFramebuffer(GL_FRAMEBUFFER, 0);
    gl_.BindVertexArray(0);
    gl_.UseProgram(0);
    gl::check_gl(gl_, "picking a patch");
    return item;
}

Image SceneRenderer::render_linear(const glm::mat4& view_projection, int width, int height) {
    gl::ItemTarget target = gl::make_color_target(gl_, width, height);  // leaves its framebuffer bound
    prepare(gl_, width, height);
    const float black[4] = {0.0f, 0.0f, 0.0f, 0.0f};
    const float far_depth = 1.0f;
    gl_.ClearBufferfv(GL_COLOR, 0, black);
    gl_.ClearBufferfv(GL_DEPTH, 0, &far_depth);
    gl_.UseProgram(scene_.id());
    gl_.Uniform1i(gl_.GetUniformLocation(scene_.id(), "u_mode"), 1);
    draw_triangles(view_projection, scene_);
    Image image{width, height, std::vector<float>(4ull * width * height)};
    gl_.PixelStorei(GL_PACK_ALIGNMENT, 4);
    gl_.ReadPixels(0, 0, width, height, GL_RGBA, GL_FLOAT, image.rgba.data());
    gl_.BindFramebuffer(GL_FRAMEBUFFER, 0);
    gl_.BindVertexArray(0);
    gl_.UseProgram(0);
    gl::check_gl(gl_, "rendering the linear image");
    flip_rows(std::span<std::uint8_t>(reinterpret_cast<std::uint8_t*>(image.rgba.data()), image.rgba.size() * sizeof(float)),
              4 * sizeof(float) * static_cast<std::size_t>(width), height);
    return image;
}

std::vector<std::uint8_t> read_back_buffer(const gl::Api& gl, int width, int height) {
    std::vector<std::uint8_t> rgba(4ull * width * height);
    gl.BindFramebuffer(GL_READ_FRAMEBUFFER, 0);
    gl.ReadBuffer(GL_BACK);
    gl.PixelStorei(GL_PACK_ALIGNMENT, 1);
    gl.ReadPixels(0, 0, width, height, GL_RGBA, GL_UNSIGNED_BYTE, rgba.data());
    gl::check_gl(gl, "reading the window's pixels");
    flip_rows(rgba, 4ull * width, height);
    return rgba;
}

namespace {

// GL's rows run bottom-up; image files run top-down.
void flip_rows(std::span<std::uint8_t> pixels, std::size_t row_bytes, int height) {
    std::vector<std::uint8_t> tmp(row_bytes);
    for (int y = 0; y < height / 2; ++y) {
        std::uint8_t* a = pixels.data() + row_bytes * y;
        std::uint8_t* b = pixels.data() + row_bytes * (height - 1 - y);
        std::copy(a, a + row_bytes, tmp.data());
        std::copy(b, b + row_bytes, a);
        std::copy(tmp.data(), tmp.data() + row_bytes, b);
    }
}

}  // namespace

}  // namespace ffcube
