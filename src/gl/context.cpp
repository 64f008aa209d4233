#include "ffcube/gl/context.hpp"

#include "gl/gl_api.hpp"  // first: glcorearb.h

#include <dlfcn.h>
#include <fmt/format.h>

#include <EGL/egl.h>
#include <EGL/eglext.h>

#include <algorithm>
#include <atomic>
#include <mutex>
#include <vector>

#include "ffcube/core/error.hpp"

namespace ffcube {

Backend parse_backend(std::string_view name) {
    if (name == "auto") return Backend::Auto;
    if (name == "egl") return Backend::Egl;
    if (name == "osmesa") return Backend::OsMesa;
    throw InputError(fmt::format("--backend {}: unknown backend (choose auto, egl or osmesa)", name));
}

std::string_view backend_name(Backend b) {
    switch (b) {
        case Backend::Auto: return "auto";
        case Backend::Egl: return "egl";
        case Backend::OsMesa: return "osmesa";
    }
    return "?";
}

GlContext::GlContext() : api_(std::make_unique<gl::Api>()) {}
GlContext::~GlContext() = default;

void GlContext::finish_setup(const std::function<void*(const char*)>& get_proc) {
    api_->load(get_proc);
    auto str = [&](GLenum e) {
        const GLubyte* s = api_->GetString(e);
        return s ? std::string(reinterpret_cast<const char*>(s)) : std::string("?");
    };
    renderer_ = str(GL_RENDERER);
    version_ = str(GL_VERSION);
    GLint major = 0, minor = 0;
    api_->GetIntegerv(GL_MAJOR_VERSION, &major);
    api_->GetIntegerv(GL_MINOR_VERSION, &minor);
    if (major * 10 + minor < 45)
        throw GlError(fmt::format("{} gives OpenGL {}.{}; ffcube needs 4.5 core", renderer_, major, minor));
}

namespace {

void* open_library(const char* const* names, std::string& why) {
    for (const char* const* n = names; *n; ++n) {
        if (void* h = dlopen(*n, RTLD_NOW | RTLD_LOCAL)) return h;
        const char* e = dlerror();
        why = e ? e : *n;
    }
    return nullptr;
}

// ----------------------------------------------------------------------------------------- EGL

struct EglLib {
    void* handle = nullptr;
    PFNEGLGETPROCADDRESSPROC GetProcAddress = nullptr;
    PFNEGLGETERRORPROC GetError = nullptr;
    PFNEGLINITIALIZEPROC Initialize = nullptr;
    PFNEGLTERMINATEPROC Terminate = nullptr;
    PFNEGLQUERYSTRINGPROC QueryString = nullptr;
    PFNEGLBINDAPIPROC BindAPI = nullptr;
    PFNEGLCHOOSECONFIGPROC ChooseConfig = nullptr;
    PFNEGLCREATECONTEXTPROC CreateContext = nullptr;
    PFNEGLDESTROYCONTEXTPROC DestroyContext = nullptr;
    PFNEGLMAKECURRENTPROC MakeCurrent = nullptr;
    PFNEGLGETPLATFORMDISPLAYEXTPROC GetPlatformDisplayEXT = nullptr;
    PFNEGLQUERYDEVICESEXTPROC QueryDevicesEXT = nullptr;
    PFNEGLQUERYDEVICESTRINGEXTPROC QueryDeviceStringEXT = nullptr;
    std::string load_error;

    static const EglLib& get() {
        static EglLib lib = [] {
            EglLib l;
            const char* names[] = {"libEGL.so.1", "libEGL.so", nullptr};
            l.handle = open_library(names, l.load_error);
            if (!l.handle) return l;
            l.GetProcAddress = reinterpret_cast<PFNEGLGETPROCADDRESSPROC>(dlsym(l.handle, "eglGetProcAddress"));
            if (!l.GetProcAddress) {
                l.load_error = "libEGL has no eglGetProcAddress";
                return l;
            }
            auto load = [&](auto& fn, const char* name) {
                fn = reinterpret_cast<std::remove_reference_t<decltype(fn)>>(l.GetProcAddress(name));
            };
            load(l.GetError, "eglGetError");
            load(l.Initialize, "eglInitialize");
            load(l.Terminate, "eglTerminate");
            load(l.QueryString, "eglQueryString");
            load(l.BindAPI, "eglBindAPI");
            load(l.ChooseConfig, "eglChooseConfig");
            load(l.CreateContext, "eglCreateContext");
            load(l.DestroyContext, "eglDestroyContext");
            load(l.MakeCurrent, "eglMakeCurrent");
            load(l.GetPlatformDisplayEXT, "eglGetPlatformDisplayEXT");
            load(l.QueryDevicesEXT, "eglQueryDevicesEXT");
            load(l.QueryDeviceStringEXT, "eglQueryDeviceStringEXT");
            if (!l.GetError || !l.Initialize || !l.CreateContext || !l.MakeCurrent || !l.BindAPI)
                l.load_error = "libEGL lacks core EGL 1.4 entry points";
            return l;
        }();
        return lib;
    }
    bool ok() const { return handle && load_error.empty(); }
};

std::string egl_error_name(EGLint e) {
    switch (e) {
        case EGL_NOT_INITIALIZED: return "EGL_NOT_INITIALIZED";
        case EGL_BAD_ACCESS: return "EGL_BAD_ACCESS";
        case EGL_BAD_ALLOC: return "EGL_BAD_ALLOC";
        case EGL_BAD_ATTRIBUTE: return "EGL_BAD_ATTRIBUTE";
        case EGL_BAD_CONFIG: return "EGL_BAD_CONFIG";
        case EGL_BAD_CONTEXT: return "EGL_BAD_CONTEXT";
        case EGL_BAD_DISPLAY: return "EGL_BAD_DISPLAY";
        case EGL_BAD_MATCH: return "EGL_BAD_MATCH";
        case EGL_BAD_PARAMETER: return "EGL_BAD_PARAMETER";
        default: return fmt::format("EGL error 0x{:04x}", e);
    }
}

bool has_extension(const char* list, std::string_view ext) {
    if (!list) return false;
    std::string_view s(list);
    for (std::size_t pos = 0; pos < s.size();) {
        std::size_t end = s.find(' ', pos);
        if (end == std::string_view::npos) end = s.size();
        if (s.substr(pos, end - pos) == ext) return true;
        pos = end + 1;
    }
    return false;
}

// An initialised EGLDisplay shared by all contexts made on it; terminated with the last one.
struct EglDisplay {
    EGLDisplay dpy = EGL_NO_DISPLAY;
    EGLConfig config = nullptr;  // nullptr = EGL_NO_CONFIG_KHR
    std::string platform;        // "egl-device" or "egl-surfaceless"
    ~EglDisplay() {
        if (dpy != EGL_NO_DISPLAY) EglLib::get().Terminate(dpy);
    }
};

// eglMakeCurrent and friends act on per-thread state; creation itself is serialised for safety.
std::mutex g_egl_mutex;

class EglContext final : public GlContext {
public:
    explicit EglContext(std::shared_ptr<EglDisplay> display) : display_(std::move(display)) {
        const EglLib& egl = EglLib::get();
        std::lock_guard lock(g_egl_mutex);
        const EGLint attribs[] = {EGL_CONTEXT_MAJOR_VERSION, 4, EGL_CONTEXT_MINOR_VERSION, 5,
                                  EGL_CONTEXT_OPENGL_PROFILE_MASK, EGL_CONTEXT_OPENGL_CORE_PROFILE_BIT, EGL_NONE};
        if (!egl.BindAPI(EGL_OPENGL_API)) throw GlError("eglBindAPI(EGL_OPENGL_API) failed: " + egl_error_name(egl.GetError()));
        ctx_ = egl.CreateContext(display_->dpy, display_->config, EGL_NO_CONTEXT, attribs);
        if (ctx_ == EGL_NO_CONTEXT)
            throw GlError("eglCreateContext (OpenGL 4.5 core) failed: " + egl_error_name(egl.GetError()));
        if (!egl.MakeCurrent(display_->dpy, EGL_NO_SURFACE, EGL_NO_SURFACE, ctx_)) {
            const EGLint e = egl.GetError();
            egl.DestroyContext(display_->dpy, ctx_);
            throw GlError("eglMakeCurrent without a surface failed: " + egl_error_name(e));
        }
        try {
            finish_setup([&](const char* name) { return reinterpret_cast<void*>(egl.GetProcAddress(name)); });
        } catch (...) {
            egl.MakeCurrent(display_->dpy, EGL_NO_SURFACE, EGL_NO_SURFACE, EGL_NO_CONTEXT);
            egl.DestroyContext(display_->dpy, ctx_);
            throw;
        }
        egl.MakeCurrent(display_->dpy, EGL_NO_SURFACE, EGL_NO_SURFACE, EGL_NO_CONTEXT);
    }
    ~EglContext() override {
        const EglLib& egl = EglLib::get();
        egl.MakeCurrent(display_->dpy, EGL_NO_SURFACE, EGL_NO_SURFACE, EGL_NO_CONTEXT);
        egl.DestroyContext(display_->dpy, ctx_);
    }
    void make_current() override {
        const EglLib& egl = EglLib::get();
        if (!egl.MakeCurrent(display_->dpy, EGL_NO_SURFACE, EGL_NO_SURFACE, ctx_))
            throw GlError("eglMakeCurrent failed: " + egl_error_name(egl.GetError()));
    }
    void release_current() override {
        EglLib::get().MakeCurrent(display_->dpy, EGL_NO_SURFACE, EGL_NO_SURFACE, EGL_NO_CONTEXT);
    }
    std::unique_ptr<GlContext> create_sibling() const override { return std::make_unique<EglContext>(display_); }
    std::string backend() const override { return display_->platform; }

private:
    std::shared_ptr<EglDisplay> display_;
    EGLContext ctx_ = EGL_NO_CONTEXT;
};

// Initialises 'dpy' and picks a config for an OpenGL context without surfaces.
std::shared_ptr<EglDisplay> init_display(EGLDisplay dpy, const std::string& platform) {
    const EglLib& egl = EglLib::get();
    if (dpy == EGL_NO_DISPLAY) throw GlError("no EGL display: " + egl_error_name(egl.GetError()));
    EGLint major = 0, minor = 0;
    if (!egl.Initialize(dpy, &major, &minor)) throw GlError("eglInitialize failed: " + egl_error_name(egl.GetError()));
    auto d = std::make_shared<EglDisplay>();
    d->dpy = dpy;
    d->platform = platform;
    const char* exts = egl.QueryString(dpy, EGL_EXTENSIONS);
    if (!has_extension(exts, "EGL_KHR_surfaceless_context"))
        throw GlError("the EGL display lacks EGL_KHR_surfaceless_context");
    const EGLint cfg_attribs[] = {EGL_RENDERABLE_TYPE, EGL_OPENGL_BIT, EGL_NONE};
    EGLint count = 0;
    EGLConfig cfg = nullptr;
    if (egl.ChooseConfig(dpy, cfg_attribs, &cfg, 1, &count) && count > 0) {
        d->config = cfg;
    } else if (!has_extension(exts, "EGL_KHR_no_config_context")) {
        throw GlError("no EGL config supports OpenGL and EGL_KHR_no_config_context is missing");
    }
    return d;
}

std::atomic<unsigned> preferred_egl_device{0};

std::unique_ptr<GlContext> create_egl(std::vector<std::string>& tried) {
    const EglLib& egl = EglLib::get();
    if (!egl.ok()) {
        tried.push_back("egl: " + egl.load_error);
        return nullptr;
    }
    const char* client_exts = egl.QueryString(EGL_NO_DISPLAY, EGL_EXTENSIONS);
    // 1. Device platform: hardware devices first (a software device is Mesa's llvmpipe again).
    if (egl.QueryDevicesEXT && egl.GetPlatformDisplayEXT && has_extension(client_exts, "EGL_EXT_platform_device")) {
        EGLDeviceEXT devices[16];
        EGLint n = 0;
        if (egl.QueryDevicesEXT(16, devices, &n) && n > 0) {
            std::vector<EGLint> hw;  // hardware devices, from the preferred one on (set_preferred_egl_device)
            for (EGLint i = 0; i < n; ++i) {
                const char* dev_exts = egl.QueryDeviceStringEXT ? egl.QueryDeviceStringEXT(devices[i], EGL_EXTENSIONS) : nullptr;
                if (!has_extension(dev_exts, "EGL_MESA_device_software")) hw.push_back(i);
            }
            if (!hw.empty())
                std::rotate(hw.begin(), hw.begin() + static_cast<std::ptrdiff_t>(preferred_egl_device % hw.size()), hw.end());
            const auto hardware = hw.size();
            for (const EGLint i : hw) {
                try {
                    auto d = init_display(egl.GetPlatformDisplayEXT(EGL_PLATFORM_DEVICE_EXT, devices[i], nullptr), "egl-device");
                    return std::make_unique<EglContext>(d);
                } catch (const GlError& e) {
                    tried.push_back(fmt::format("egl device {}: {}", i, e.what()));
                }
            }
            if (hardware == 0) tried.push_back("egl device platform: only software devices (no GPU)");
        } else {
            tried.push_back("egl device platform: no devices");
        }
    } else {
        tried.push_back("egl device platform: EGL_EXT_platform_device not offered");
    }
    // 2. Mesa's surfaceless platform.
    if (egl.GetPlatformDisplayEXT && has_extension(client_exts, "EGL_MESA_platform_surfaceless")) {
        try {
            auto d = init_display(egl.GetPlatformDisplayEXT(EGL_PLATFORM_SURFACELESS_MESA, EGL_DEFAULT_DISPLAY, nullptr),
                                  "egl-surfaceless");
            return std::make_unique<EglContext>(d);
        } catch (const GlError& e) {
            tried.push_back(std::string("egl surfaceless: ") + e.what());
        }
    } else {
        tried.push_back("egl surfaceless: EGL_MESA_platform_surfaceless not offered");
    }
    return nullptr;
}

// -------------------------------------------------------------------------------------- OSMesa
// The few OSMesa declarations ffcube needs, from Mesa's GL/osmesa.h (which drags in the
// compatibility GL/gl.h, incompatible with glcorearb.h). Values are part of Mesa's stable ABI.
using OSMesaContext = struct osmesa_context*;
constexpr int OSMESA_RGBA = GL_RGBA;
constexpr int OSMESA_FORMAT = 0x22;
constexpr int OSMESA_DEPTH_BITS = 0x30;
constexpr int OSMESA_STENCIL_BITS = 0x31;
constexpr int OSMESA_PROFILE = 0x33;
constexpr int OSMESA_CORE_PROFILE = 0x34;
constexpr int OSMESA_CONTEXT_MAJOR_VERSION = 0x36;
constexpr int OSMESA_CONTEXT_MINOR_VERSION = 0x37;

struct OsMesaLib {
    void* handle = nullptr;
    OSMesaContext (*CreateContextAttribs)(const int*, OSMesaContext) = nullptr;
    void (*DestroyContext)(OSMesaContext) = nullptr;
    GLboolean (*MakeCurrent)(OSMesaContext, void*, GLenum, GLsizei, GLsizei) = nullptr;
    void (*(*GetProcAddress)(const char*))() = nullptr;
    std::string load_error;

    static const OsMesaLib& get() {
        static OsMesaLib lib = [] {
            OsMesaLib l;
            const char* names[] = {"libOSMesa.so.8", "libOSMesa.so", nullptr};
            l.handle = open_library(names, l.load_error);
            if (!l.handle) return l;
            auto load = [&](auto& fn, const char* name) {
                fn = reinterpret_cast<std::remove_reference_t<decltype(fn)>>(dlsym(l.handle, name));
                if (!fn) l.load_error = std::string("libOSMesa lacks ") + name;
            };
            load(l.CreateContextAttribs, "OSMesaCreateContextAttribs");
            load(l.DestroyContext, "OSMesaDestroyContext");
            load(l.MakeCurrent, "OSMesaMakeCurrent");
            load(l.GetProcAddress, "OSMesaGetProcAddress");
            return l;
        }();
        return lib;
    }
    bool ok() const { return handle && load_error.empty(); }
};

class OsMesaContext final : public GlContext {
public:
    OsMesaContext() {
        const OsMesaLib& os = OsMesaLib::get();
        const int attribs[] = {OSMESA_FORMAT, OSMESA_RGBA, OSMESA_DEPTH_BITS, 0, OSMESA_STENCIL_BITS, 0,
                               OSMESA_PROFILE, OSMESA_CORE_PROFILE, OSMESA_CONTEXT_MAJOR_VERSION, 4,
                               OSMESA_CONTEXT_MINOR_VERSION, 5, 0};
        ctx_ = os.CreateContextAttribs(attribs, nullptr);
        if (!ctx_) throw GlError("OSMesaCreateContextAttribs (OpenGL 4.5 core) failed");
        make_current();
        try {
            finish_setup([&](const char* name) { return reinterpret_cast<void*>(os.GetProcAddress(name)); });
        } catch (...) {
            os.DestroyContext(ctx_);
            throw;
        }
        release_current();
    }
    ~OsMesaContext() override { OsMesaLib::get().DestroyContext(ctx_); }
    void make_current() override {
        // OSMesa needs a colour buffer to make a context current; ffcube renders to FBOs, so a
        // 1×1 buffer is enough.
        if (!OsMesaLib::get().MakeCurrent(ctx_, pixel_, GL_UNSIGNED_BYTE, 1, 1)) throw GlError("OSMesaMakeCurrent failed");
    }
    void release_current() override { OsMesaLib::get().MakeCurrent(nullptr, nullptr, 0, 0, 0); }
    std::unique_ptr<GlContext> create_sibling() const override { return std::make_unique<OsMesaContext>(); }
    std::string backend() const override { return "osmesa"; }

private:
    OSMesaContext ctx_ = nullptr;
    unsigned char pixel_[4] = {0, 0, 0, 0};
};

std::unique_ptr<GlContext> create_osmesa(std::vector<std::string>& tried) {
    const OsMesaLib& os = OsMesaLib::get();
    if (!os.ok()) {
        tried.push_back("osmesa: " + os.load_error);
        return nullptr;
    }
    try {
        return std::make_unique<OsMesaContext>();
    } catch (const GlError& e) {
        tried.push_back(std::string("osmesa: ") + e.what());
        return nullptr;
    }
}

}  // namespace

namespace {
std::atomic<bool> g_context_created{false};
}

bool gl::context_created_in_process() { return g_context_created; }

void set_preferred_egl_device(unsigned index) { preferred_egl_device = index; }

std::unique_ptr<GlContext> create_headless_context(Backend backend) {
    std::vector<std::string> tried;
    std::unique_ptr<GlContext> ctx;
    if (backend == Backend::Auto || backend == Backend::Egl) ctx = create_egl(tried);
    if (!ctx && (backend == Backend::Auto || backend == Backend::OsMesa)) ctx = create_osmesa(tried);
    if (ctx) {
        g_context_created = true;
        return ctx;
    }
    std::string msg = fmt::format("no OpenGL 4.5 core context could be created (--backend {}); tried:", backend_name(backend));
    for (const auto& t : tried) msg += "\n  - " + t;
    throw GlError(msg);
}

}  // namespace ffcube
