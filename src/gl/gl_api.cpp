#include "gl/gl_api.hpp"

#include <fmt/format.h>

#include "ffcube/core/error.hpp"

namespace ffcube::gl {

void Api::load(const std::function<void*(const char*)>& get_proc) {
#define FFCUBE_GL_LOAD(name)                                                                   \
    name = reinterpret_cast<decltype(name)>(get_proc("gl" #name));                             \
    if (!name) throw GlError("OpenGL entry point gl" #name " is missing (need OpenGL 4.5 core)");
    FFCUBE_GL_FUNCTIONS(FFCUBE_GL_LOAD)
#undef FFCUBE_GL_LOAD
}

void check_gl(const Api& gl, const char* what) {
    const GLenum e = gl.GetError();
    if (e != GL_NO_ERROR) throw GlError(fmt::format("OpenGL error 0x{:04x} in {}", static_cast<unsigned>(e), what));
}

}  // namespace ffcube::gl
