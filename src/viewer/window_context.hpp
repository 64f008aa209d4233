// The GLFW window's OpenGL 4.5 core context: the third GlContext beside EGL and OSMesa. Its
// entry points come from glfwGetProcAddress into the same gl::Api table, so the viewer, like the
// rest of ffcube, never calls a gl* symbol directly.
#pragma once

#include <memory>
#include <string>

#include "ffcube/gl/context.hpp"

struct GLFWwindow;

namespace ffcube {

class WindowContext final : public GlContext {
public:
    // Opens a window of width × height screen coordinates and makes its context current on the
    // calling thread. Throws GlError with GLFW's reason (no DISPLAY, no GL 4.5 core, ...).
    WindowContext(int width, int height, const std::string& title);
    ~WindowContext() override;

    void make_current() override;
    void release_current() override;
    // A hidden 1×1 window whose context shares this one's objects (for a loader thread).
    std::unique_ptr<GlContext> create_sibling() const override;
    std::string backend() const override { return "glfw"; }

    GLFWwindow* window() const { return window_; }

private:
    WindowContext(int width, int height, const std::string& title, bool visible, GLFWwindow* share);
    GLFWwindow* window_ = nullptr;
};

}  // namespace ffcube
