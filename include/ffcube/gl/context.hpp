// Headless OpenGL 4.5 core contexts behind one interface. No GL, EGL or OSMesa type appears
// here: the entry-point table (gl::Api) is opaque to users of this header.
//
// Backends, tried in this order by Backend::Auto:
//   1. EGL device platform, a hardware device (an NVIDIA GPU on a headless server);
//   2. EGL surfaceless platform (Mesa; llvmpipe when there is no GPU);
//   3. OSMesa (Mesa's off-screen library; llvmpipe).
// Both libraries are loaded at run time (dlopen), so one binary offers both and a missing
// library is just a reason in the error message.
#pragma once

#include <functional>
#include <memory>
#include <string>
#include <string_view>

namespace ffcube {

namespace gl {
struct Api;
}

enum class Backend { Auto, Egl, OsMesa };

// "auto", "egl", "osmesa"; throws InputError for anything else.
Backend parse_backend(std::string_view name);
std::string_view backend_name(Backend b);

// One GL context. Current on at most one thread at a time; make_current() binds it to the
// calling thread (rendering goes to framebuffer objects: there is no default framebuffer).
class GlContext {
public:
    virtual ~GlContext();
    GlContext(const GlContext&) = delete;
    GlContext& operator=(const GlContext&) = delete;

    virtual void make_current() = 0;
    virtual void release_current() = 0;
    // Another context on the same backend and device, for another worker thread.
    virtual std::unique_ptr<GlContext> create_sibling() const = 0;
    // e.g. "egl-device", "egl-surfaceless", "osmesa".
    virtual std::string backend() const = 0;
    // GL_RENDERER, e.g. "llvmpipe (LLVM 15.0.6, 256 bits)". Valid after construction.
    const std::string& renderer() const { return renderer_; }
    const std::string& version() const { return version_; }
    // Entry points; valid while this context is current on the calling thread.
    const gl::Api& api() const { return *api_; }

protected:
    GlContext();
    // Loads the entry points and reads GL_RENDERER; call with the context current.
    void finish_setup(const std::function<void*(const char*)>& get_proc);

private:
    std::unique_ptr<gl::Api> api_;
    std::string renderer_, version_;
};

// Creates a context with the requested backend (Auto: see above). Throws GlError listing every
// backend tried and why it failed. The returned context is not current on any thread.
std::unique_ptr<GlContext> create_headless_context(Backend backend);

// Which hardware EGL device the device platform tries first: device (index mod the number of
// hardware devices) of the ones EGL lists, then the others in order. 0 (the default) is the
// first. Several processes on one node (MPI ranks) each pass their local rank, so that each
// drives its own GPU (src/mpi, docs/scaling.md). Set before the first context is created.
void set_preferred_egl_device(unsigned index);

}  // namespace ffcube
