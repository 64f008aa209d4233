#include "window_context.hpp"

#define GLFW_INCLUDE_NONE  // GL declarations come from gl/gl_api.hpp (glcorearb.h), never gl.h
#include <GLFW/glfw3.h>
#include <fmt/format.h>

#include "ffcube/core/error.hpp"

namespace ffcube {
namespace {

// glfwInit/glfwTerminate bracket the life of all windows; contexts are made on the main thread.
int g_windows = 0;

std::string glfw_reason() {
    const char* description = nullptr;
    glfwGetError(&description);
    return description ? description : "no reason given";
}

}  // namespace

WindowContext::WindowContext(int width, int height, const std::string& title)
    : WindowContext(width, height, title, true, nullptr) {}

WindowContext::WindowContext(int width, int height, const std::string& title, bool visible, GLFWwindow* share) {
    if (g_windows == 0 && !glfwInit()) throw GlError(fmt::format("cannot open a window: GLFW: {}", glfw_reason()));
    ++g_windows;
    glfwDefaultWindowHints();
    glfwWindowHint(GLFW_CONTEXT_VERSION_MAJOR, 4);
    glfwWindowHint(GLFW_CONTEXT_VERSION_MINOR, 5);
    glfwWindowHint(GLFW_OPENGL_PROFILE, GLFW_OPENGL_CORE_PROFILE);
    glfwWindowHint(GLFW_OPENGL_FORWARD_COMPAT, GLFW_TRUE);
    glfwWindowHint(GLFW_VISIBLE, visible ? GLFW_TRUE : GLFW_FALSE);
    // Screenshots read the back buffer: keep it 8-bit RGBA, single-sampled.
    glfwWindowHint(GLFW_SAMPLES, 0);
    window_ = glfwCreateWindow(width, height, title.c_str(), nullptr, share);
    if (!window_) {
        const std::string reason = glfw_reason();
        if (--g_windows == 0) glfwTerminate();
        throw GlError(fmt::format("cannot open a {}x{} window with an OpenGL 4.5 core context: GLFW: {}", width, height, reason));
    }
    glfwMakeContextCurrent(window_);
    finish_setup([](const char* name) { return reinterpret_cast<void*>(glfwGetProcAddress(name)); });
}

WindowContext::~WindowContext() {
    glfwDestroyWindow(window_);
    if (--g_windows == 0) glfwTerminate();
}

void WindowContext::make_current() { glfwMakeContextCurrent(window_); }
void WindowContext::release_current() { glfwMakeContextCurrent(nullptr); }

std::unique_ptr<GlContext> WindowContext::create_sibling() const {
    GLFWwindow* previous = glfwGetCurrentContext();
    std::unique_ptr<GlContext> sibling(new WindowContext(1, 1, "ffcube sibling", false, window_));
    // Like the headless backends, a new context is not left current.
    glfwMakeContextCurrent(previous);
    return sibling;
}

}  // namespace ffcube
