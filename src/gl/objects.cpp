#include "gl/objects.hpp"

#include <fmt/format.h>

#include <vector>

#include "ffcube/core/error.hpp"

namespace ffcube::gl {

Buffer make_buffer(const Api& gl) {
    GLuint id = 0;
    gl.GenBuffers(1, &id);
    return Buffer(gl, id);
}
VertexArray make_vertex_array(const Api& gl) {
    GLuint id = 0;
    gl.GenVertexArrays(1, &id);
    return VertexArray(gl, id);
}
Texture make_texture(const Api& gl) {
    GLuint id = 0;
    gl.GenTextures(1, &id);
    return Texture(gl, id);
}
Framebuffer make_framebuffer(const Api& gl) {
    GLuint id = 0;
    gl.GenFramebuffers(1, &id);
    return Framebuffer(gl, id);
}
Renderbuffer make_renderbuffer(const Api& gl) {
    GLuint id = 0;
    gl.GenRenderbuffers(1, &id);
    return Renderbuffer(gl, id);
}

namespace {
GLuint compile(const Api& gl, GLenum type, std::string_view name, std::string_view src) {
    const GLuint s = gl.CreateShader(type);
    const GLchar* text = src.data();
    const GLint len = static_cast<GLint>(src.size());
    gl.ShaderSource(s, 1, &text, &len);
    gl.CompileShader(s);
    GLint ok = 0;
    gl.GetShaderiv(s, GL_COMPILE_STATUS, &ok);
    if (!ok) {
        GLint log_len = 0;
        gl.GetShaderiv(s, GL_INFO_LOG_LENGTH, &log_len);
        std::vector<char> log(static_cast<std::size_t>(std::max(log_len, 1)));
        gl.GetShaderInfoLog(s, log_len, nullptr, log.data());
        gl.DeleteShader(s);
        throw GlError(fmt::format("compiling {} ({} shader) failed:\n{}", name,
                                  type == GL_VERTEX_SHADER ? "vertex" : "fragment", log.data()));
    }
    return s;
}
}  // namespace

Program make_program(const Api& gl, std::string_view name, std::string_view vertex_src, std::string_view fragment_src) {
    const GLuint vs = compile(gl, GL_VERTEX_SHADER, name, vertex_src);
    GLuint fs = 0;
    try {
        fs = compile(gl, GL_FRAGMENT_SHADER, name, fragment_src);
    } catch (...) {
        gl.DeleteShader(vs);
        throw;
    }
    Program p(gl, gl.CreateProgram());
    gl.AttachShader(p.id(), vs);
    gl.AttachShader(p.id(), fs);
    gl.LinkProgram(p.id());
    gl.DeleteShader(vs);
    gl.DeleteShader(fs);
    GLint ok = 0;
    gl.GetProgramiv(p.id(), GL_LINK_STATUS, &ok);
    if (!ok) {
        GLint log_len = 0;
        gl.GetProgramiv(p.id(), GL_INFO_LOG_LENGTH, &log_len);
        std::vector<char> log(static_cast<std::size_t>(std::max(log_len, 1)));
        gl.GetProgramInfoLog(p.id(), log_len, nullptr, log.data());
        throw GlError(fmt::format("linking {} failed:\n{}", name, log.data()));
    }
    return p;
}

namespace {
ItemTarget make_target(const Api& gl, int width, int height, GLenum color_format, const char* what) {
    ItemTarget t;
    t.width = width;
    t.height = height;
    t.color = make_texture(gl);
    gl.BindTexture(GL_TEXTURE_2D, t.color.id());
    gl.TexStorage2D(GL_TEXTURE_2D, 1, color_format, width, height);
    gl.TexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, GL_NEAREST);
    gl.TexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER, GL_NEAREST);
    gl.BindTexture(GL_TEXTURE_2D, 0);
    t.depth = make_renderbuffer(gl);
    gl.BindRenderbuffer(GL_RENDERBUFFER, t.depth.id());
    gl.RenderbufferStorage(GL_RENDERBUFFER, GL_DEPTH_COMPONENT32F, width, height);
    gl.BindRenderbuffer(GL_RENDERBUFFER, 0);
    t.fbo = make_framebuffer(gl);
    gl.BindFramebuffer(GL_FRAMEBUFFER, t.fbo.id());
    gl.FramebufferTexture2D(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, GL_TEXTURE_2D, t.color.id(), 0);
    gl.FramebufferRenderbuffer(GL_FRAMEBUFFER, GL_DEPTH_ATTACHMENT, GL_RENDERBUFFER, t.depth.id());
    const GLenum draw = GL_COLOR_ATTACHMENT0;
    gl.DrawBuffers(1, &draw);
    gl.ReadBuffer(GL_COLOR_ATTACHMENT0);
    const GLenum status = gl.CheckFramebufferStatus(GL_FRAMEBUFFER);
    if (status != GL_FRAMEBUFFER_COMPLETE)
        throw GlError(fmt::format("{} framebuffer {}x{} incomplete (status 0x{:04x})", what, width, height, status));
    check_gl(gl, what);
    return t;
}
}  // namespace

ItemTarget make_item_target(const Api& gl, int width, int height) {
    return make_target(gl, width, height, GL_R32UI, "item buffer");
}
ItemTarget make_color_target(const Api& gl, int width, int height) {
    return make_target(gl, width, height, GL_RGBA32F, "colour");
}

}  // namespace ffcube::gl
