// The OpenGL 4.5 core entry points ffcube uses, as a table of function pointers filled from the
// current backend's get-proc-address (EGL, OSMesa or GLFW). ffcube never links libGL/libOpenGL
// and never calls a gl* symbol directly: with both EGL and OSMesa in one binary, a direct call
// would bind to whichever library exported it first. tests/gl checks the binary imports no gl*.
#pragma once

#define GL_GLEXT_PROTOTYPES 1  // declarations only, for decltype below; nothing is linked
#include <GL/glcorearb.h>

#include <functional>

#define FFCUBE_GL_FUNCTIONS(X)                                                                  \
    X(GetString) X(GetIntegerv) X(GetError) X(Enable) X(Disable) X(Viewport) X(Scissor)          \
    X(ClearBufferuiv) X(ClearBufferfv) X(DepthFunc) X(DepthMask) X(ColorMask) X(ClipControl)     \
    X(PixelStorei) X(ReadPixels) X(ReadBuffer) X(DrawBuffers) X(Finish) X(Flush)                 \
    X(GenBuffers) X(DeleteBuffers) X(BindBuffer) X(BufferData) X(BufferSubData)                  \
    X(GenVertexArrays) X(DeleteVertexArrays) X(BindVertexArray) X(EnableVertexAttribArray)       \
    X(VertexAttribPointer) X(VertexAttribIPointer) X(GenTextures) X(DeleteTextures)              \
    X(BindTexture) X(ActiveTexture) X(TexStorage2D) X(TexBuffer) X(TexParameteri)                \
    X(GenFramebuffers) X(DeleteFramebuffers) X(BindFramebuffer) X(FramebufferTexture2D)          \
    X(CheckFramebufferStatus) X(GenRenderbuffers) X(DeleteRenderbuffers) X(BindRenderbuffer)     \
    X(RenderbufferStorage) X(FramebufferRenderbuffer) X(CreateShader) X(ShaderSource)            \
    X(CompileShader) X(GetShaderiv) X(GetShaderInfoLog) X(DeleteShader) X(CreateProgram)         \
    X(AttachShader) X(LinkProgram) X(GetProgramiv) X(GetProgramInfoLog) X(DeleteProgram)         \
    X(UseProgram) X(GetUniformLocation) X(Uniform1i) X(Uniform1ui) X(Uniform1f) X(Uniform3f)      \
    X(UniformMatrix4fv) X(DrawElements) X(DrawArrays) X(PolygonMode) X(LineWidth) X(BlendFunc)   \
    X(ClearColor) X(ClearDepth) X(Clear) X(CullFace) X(FrontFace) X(PolygonOffset) X(TexImage2D)  \
    X(TexSubImage2D) X(BlitFramebuffer) X(GetTexImage) X(BindBufferBase) X(VertexAttribLPointer)

namespace ffcube::gl {

struct Api {
#define FFCUBE_GL_MEMBER(name) decltype(&::gl##name) name = nullptr;
    FFCUBE_GL_FUNCTIONS(FFCUBE_GL_MEMBER)
#undef FFCUBE_GL_MEMBER

    // Fills every entry from get_proc; throws GlError naming the first missing entry point.
    void load(const std::function<void*(const char*)>& get_proc);
};

// Whether create_headless_context has ever succeeded in this process (fork-safety check).
bool context_created_in_process();

// Throws GlError with 'what' and the GL error code when glGetError reports one.
void check_gl(const Api& gl, const char* what);

}  // namespace ffcube::gl
