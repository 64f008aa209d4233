// RAII wrappers for GL objects: move-only, one GLuint each, deleted through the Api of the
// context that made them (which must be current when they are destroyed).
#pragma once

#include <string>
#include <string_view>
#include <utility>

#include "gl/gl_api.hpp"

namespace ffcube::gl {

template <void (*Delete)(const Api&, GLuint)>
class Object {
public:
    Object() = default;
    Object(const Api& api, GLuint id) : api_(&api), id_(id) {}
    ~Object() { reset(); }
    Object(Object&& o) noexcept : api_(o.api_), id_(std::exchange(o.id_, 0)) {}
    Object& operator=(Object&& o) noexcept {
        if (this != &o) {
            reset();
            api_ = o.api_;
            id_ = std::exchange(o.id_, 0);
        }
        return *this;
    }
    Object(const Object&) = delete;
    Object& operator=(const Object&) = delete;

    GLuint id() const { return id_; }
    explicit operator bool() const { return id_ != 0; }
    void reset() {
        if (id_ != 0) Delete(*api_, id_);
        id_ = 0;
    }

private:
    const Api* api_ = nullptr;
    GLuint id_ = 0;
};

inline void delete_buffer(const Api& gl, GLuint id) { gl.DeleteBuffers(1, &id); }
inline void delete_vertex_array(const Api& gl, GLuint id) { gl.DeleteVertexArrays(1, &id); }
inline void delete_texture(const Api& gl, GLuint id) { gl.DeleteTextures(1, &id); }
inline void delete_framebuffer(const Api& gl, GLuint id) { gl.DeleteFramebuffers(1, &id); }
inline void delete_renderbuffer(const Api& gl, GLuint id) { gl.DeleteRenderbuffers(1, &id); }
inline void delete_program(const Api& gl, GLuint id) { gl.DeleteProgram(id); }

using Buffer = Object<delete_buffer>;
using VertexArray = Object<delete_vertex_array>;
using Texture = Object<delete_texture>;
using Framebuffer = Object<delete_framebuffer>;
using Renderbuffer = Object<delete_renderbuffer>;
using Program = Object<delete_program>;

Buffer make_buffer(const Api& gl);
VertexArray make_vertex_array(const Api& gl);
Texture make_texture(const Api& gl);
Framebuffer make_framebuffer(const Api& gl);
Renderbuffer make_renderbuffer(const Api& gl);
// Compiles and links; throws GlError with the info log (and the shader's name) on failure.
Program make_program(const Api& gl, std::string_view name, std::string_view vertex_src, std::string_view fragment_src);

// An R32UI colour target with a 32-bit float depth buffer: the item buffer. No MSAA, no blending,
// no sRGB: an integer attachment cannot have them.
struct ItemTarget {
    Framebuffer fbo;
    Texture color;
    Renderbuffer depth;
    int width = 0, height = 0;
};
ItemTarget make_item_target(const Api& gl, int width, int height);

// An RGBA32F colour target with float depth, for rendering images of the solved scene.
ItemTarget make_color_target(const Api& gl, int width, int height);

}  // namespace ffcube::gl
