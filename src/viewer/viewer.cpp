#include "ffcube/viewer/viewer.hpp"

#define GLFW_INCLUDE_NONE  // GL declarations come from gl/gl_api.hpp (glcorearb.h), never gl.h
#include <numbers>
#include <GLFW/glfw3.h>
#include <fmt/format.h>
#include <imgui.h>
#include <backends/imgui_impl_glfw.h>
#include <backends/imgui_impl_opengl3.h>

#include <algorithm>
#include <cmath>
#include <deque>
#include <filesystem>
#include <future>
#include <optional>

#include "ffcube/core/error.hpp"
#include "ffcube/core/log.hpp"
#include "ffcube/core/timer.hpp"
#include "ffcube/solver/progressive.hpp"
#include "ffcube/viewer/camera.hpp"
#include "ffcube/viewer/display.hpp"
#include "ffcube/render/image.hpp"
#include "renderer.hpp"
#include "window_context.hpp"

namespace ffcube {
namespace {

ToneMap parse_tone_map(const std::string& name) {
    if (name == "clamp") return ToneMap::Clamp;
    if (name == "reinhard") return ToneMap::Reinhard;
    if (name == "aces") return ToneMap::Aces;
    throw InputError(fmt::format("--tone-map {}: must be clamp, reinhard or aces", name));
}

// Dear ImGui's context and its GLFW and OpenGL3 backends, for the life of the window. The OpenGL3
// backend loads its own entry points (dlopen of libGL), so it adds no gl* import to ffcube.
class ImGuiSession {
public:
    explicit ImGuiSession(GLFWwindow* window) {
        IMGUI_CHECKVERSION();
        ImGui::CreateContext();
        ImGui::GetIO().IniFilename = nullptr;  // never write imgui.ini into the user's directory
        ImGui::StyleColorsDark();
        if (!ImGui_ImplGlfw_InitForOpenGL(window, true) || !ImGui_ImplOpenGL3_Init("#version 450")) {
            ImGui::DestroyContext();
            throw GlError("Dear ImGui could not start its GLFW/OpenGL3 backends");
        }
    }
    ~ImGuiSession() {
        ImGui_ImplOpenGL3_Shutdown();
        ImGui_ImplGlfw_Shutdown();
        ImGui::DestroyContext();
    }
    ImGuiSession(const ImGuiSession&) = delete;
    ImGuiSession& operator=(const ImGuiSession&) = delete;
};

// Unshot fraction against solver time, resampled evenly in time for ImGui::PlotLines.
class ConvergencePlot {
public:
    void clear() { samples_.clear(); }
    void add(double seconds, double unshot) {
        // Thinned by half when full: the whole run stays covered at a bounded cost.
        if (samples_.size() == kCapacity) {
            for (std::size_t k = 0; k < kCapacity / 2; ++k) samples_[k] = samples_[2 * k];
            samples_.resize(kCapacity / 2);
        }
        samples_.push_back({seconds, unshot});
    }
    void draw() const {
        if (samples_.size() < 2) {
            ImGui::TextUnformatted("(the plot starts after two frames of shooting)");
            return;
        }
        const std::string caption = fmt::format("log10 unshot, 0..{:.2f} s", samples_.back().seconds);
        ImGui::PlotLines("##unshot", &ConvergencePlot::value, const_cast<ConvergencePlot*>(this), kPoints, 0,
                         caption.c_str(), FLT_MAX, FLT_MAX, ImVec2(300, 80));
    }

private:
    struct Sample {
        double seconds, unshot;
    };
    static constexpr std::size_t kCapacity = 4096;
    static constexpr int kPoints = 200;
    static float value(void* data, int idx) {
        const auto& s = static_cast<const ConvergencePlot*>(data)->samples_;
        const double t = s.back().seconds * idx / (kPoints - 1);
        const auto it = std::lower_bound(s.begin(), s.end(), t, [](const Sample& a, double x) { return a.seconds < x; });
        const double u = it == s.end() ? s.back().unshot : it->unshot;
        return static_cast<float>(std::log10(std::max(u, 1e-12)));
    }
    std::vector<Sample> samples_;
};

// A hemicube's item buffer (3N × N atlas, row 0 at the bottom) as an RGBA8 texture for ImGui.
struct HemicubeImage {
    gl::Texture texture;
    int width = 0, height = 0;

    void upload(const gl::Api& gl, const std::vector<std::uint32_t>& items, int resolution) {
        width = 3 * resolution, height = resolution;
        FFCUBE_CHECK_MSG(items.size() == static_cast<std::size_t>(width) * height, "atlas of 3N x N items");
        std::vector<std::uint32_t> rgba(items.size());
        std::transform(items.begin(), items.end(), rgba.begin(), item_color);
        texture = gl::make_texture(gl);
        gl.BindTexture(GL_TEXTURE_2D, texture.id());
        gl.TexStorage2D(GL_TEXTURE_2D, 1, GL_RGBA8, width, height);
        gl.TexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, GL_NEAREST);
        gl.TexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER, GL_NEAREST);
        gl.PixelStorei(GL_UNPACK_ALIGNMENT, 4);
        gl.TexSubImage2D(GL_TEXTURE_2D, 0, 0, 0, width, height, GL_RGBA, GL_UNSIGNED_BYTE, rgba.data());
        gl.BindTexture(GL_TEXTURE_2D, 0);
        gl::check_gl(gl, "uploading the hemicube image");
    }
};

// The next free "ffcube-view-NNN.EXT" in the current directory.
std::string next_file_name(const char* extension) {
    for (int k = 1;; ++k) {
        std::string name = fmt::format("ffcube-view-{:03d}.{}", k, extension);
        if (!std::filesystem::exists(name)) return name;
    }
}

class Viewer {
public:
    Viewer(ViewerLevels& levels, const SolverOptions& solver_options, const ViewerOptions& o)
        : levels_(levels),
          solver_options_(solver_options),
          options_(o),
          solver_(std::make_unique<ProgressiveSolver>(levels.scene(), levels.provider(), solver_options)),
          window_(o.width, o.height, levels.scene().source.empty() ? "ffcube view" : "ffcube view: " + levels.scene().source),
          imgui_(window_.window()),
          obstructions_(build_obstruction_mesh(levels.scene())),
          camera_(OrbitCamera::frame(levels.scene())),
          tone_map_(parse_tone_map(o.tone_map)),
          ambient_(o.ambient),
          smooth_(!o.flat),
          wireframe_(o.wireframe),
          show_ui_(!o.hide_ui),
          paused_(o.paused) {
        upload_level();
        exposure_ = static_cast<float>(o.exposure ? *o.exposure : default_exposure());
        glfwSwapInterval(scripted() ? 0 : 1);  // scripted runs do not wait for the display
        info("viewer: {} patches, window {}x{} on {} ({})", scene().size(), o.width, o.height, window_.renderer(),
             window_.version());
        if (obstructions_.patches > 0)
            info("viewer: {} obstruction-only patches drawn as translucent glass (no radiosity; O toggles them)",
                 obstructions_.patches);
    }

    void run() {
        // A scripted run shoots in frames 0 .. N-1, then draws two more frames without shooting:
        // the first picks, the second is saved (Dear ImGui sizes a newly shown window during one
        // frame before it draws it).
        // With --until-done the settling frames start once the last level's solve has stopped.
        int settle_from = options_.until_done ? std::numeric_limits<int>::max() : options_.frames;
        for (int frame = 0; !glfwWindowShouldClose(window_.window()); ++frame) {
            const bool scripted = this->scripted();
            const bool settling = scripted && frame >= settle_from;
            const bool last = settling && frame - settle_from == 1;  // (settle_from + 1 would overflow at max)
            if (scripted || solving()) glfwPollEvents();
            else glfwWaitEventsTimeout(0.1);  // idle: no busy loop while nothing changes

            ImGui_ImplOpenGL3_NewFrame();
            ImGui_ImplGlfw_NewFrame();
            ImGui::NewFrame();
            handle_input();
            if (settling && !last && options_.pick) pick_window_pixel(options_.pick->first, options_.pick->second);
            if (show_ui_) draw_panels();  // its buttons may step or reset: the solver is idle here
            ImGui::Render();

            int width = 0, height = 0;
            glfwGetFramebufferSize(window_.window(), &width, &height);
            const bool draw = width > 0 && height > 0;
            // The picture shows the state before this frame's shots (read now, before they start).
            if (draw) renderer_->set_colors(colors());
            // This frame's shots run on a thread while this thread draws: the rows are measured
            // in the worker processes (forked before the window existed), which would otherwise
            // idle while the window's context draws. The step's budget is the solver time per
            // frame, or the previous frame's drawing if that took longer (no idle workers then).
            // Saving an image reads the solver: that frame shoots first, then draws.
            const bool shoot = !settling && solving();
            const bool saving = !save_png_.empty() || !save_exr_.empty() || last;
            const double frame_start = glfwGetTime();
            const std::uint64_t shots_before = solver_->shots();
            if (shoot && shots_while_shooting_ == 0 && shooting_end_ == 0.0) shooting_start_ = frame_start;
            const StepBudget budget{options_.shots_per_frame ? options_.shots_per_frame : std::numeric_limits<std::uint64_t>::max(),
                                    std::max(options_.budget_ms / 1000.0, draw_seconds_)};
            std::future<double> stepping;
            if (shoot && !saving) {
                stepping = std::async(std::launch::async, [this, budget] {
                    Stopwatch watch;
                    solver_->step(budget);
                    return watch.seconds();
                });
            } else if (shoot) {
                step(budget);
                if (draw) renderer_->set_colors(colors());
            }
            Stopwatch drawing;
            if (draw) {
                renderer_->draw(settings(width, height), width, height);
                ImGui_ImplOpenGL3_RenderDrawData(ImGui::GetDrawData());
                if (!save_png_.empty()) write_screenshot(std::exchange(save_png_, {}), width, height);
                if (!save_exr_.empty()) write_linear(std::exchange(save_exr_, {}), width, height);
                if (last) {
                    if (!options_.screenshot.empty()) write_screenshot(options_.screenshot, width, height);
                    if (!options_.exr.empty()) write_linear(options_.exr, width, height);
                }
            }
            glfwSwapBuffers(window_.window());
            draw_seconds_ = drawing.seconds();
            if (stepping.valid()) record_step(stepping.get());
            if (shoot) {
                shooting_end_ = glfwGetTime();
                shots_while_shooting_ += solver_->shots() - shots_before;
            }
            if (close_inspector_) inspected_.reset(), close_inspector_ = false;
            if (last) break;
            // Between frames (no shots running): a level whose solve stopped hands over to the next
            // (not while a scripted run settles: its pick and its picture are of one level).
            if (!settling && !levels_done_ && solver_->status() != StopReason::Running) next_level();
            if (options_.until_done && !settling && levels_done_)
                settle_from = frame + 1;
        }
        // Over the frames that shot: the throughput tools/bench_viewer.sh reads.
        const double shooting = shooting_end_ - shooting_start_;
        if (levels_.level() > 0)
            info("viewer: {} adaptive levels shown, the last with {} elements", levels_.level() + 1, scene().size());
        info("viewer: {} shots, unshot fraction {:.3g}; {} shots in {:.2f} s of frames that shot ({:.1f} shots/s)", earlier_shots_ + solver_->shots(),
             solver_->unshot_fraction(), shots_while_shooting_, shooting,
             shooting > 0 ? static_cast<double>(shots_while_shooting_) / shooting : 0.0);
    }

    SolveResult result() const { return solver_->result(); }

private:
    bool scripted() const { return options_.frames > 0 || options_.until_done; }
    const Scene& scene() const { return levels_.scene(); }

    // The display mesh and its GPU buffers for the current level's scene.
    void upload_level() {
        renderer_.reset();  // it refers to the mesh replaced now
        const std::span<const std::uint32_t> origin = levels_.origin();
        mesh_ = build_display_mesh(scene(), origin);
        start_patches_ = origin.empty() ? 0 : 1 + static_cast<std::size_t>(*std::max_element(origin.begin(), origin.end()));
        renderer_.emplace(window_.api(), mesh_, obstructions_);
    }

    // The level's solve stopped: the levels estimate and refine. The last level stays on screen with
    // its solver; otherwise the old solver goes first (it refers to the old level's scene and rows),
    // then the new level gets its own solver, display mesh and buffers.
    void next_level() {
        if (!levels_.finish(solver_->result())) {
            levels_done_ = true;
            return;
        }
        earlier_shots_ += solver_->shots();
        solver_.reset();
        levels_.advance();
        inspected_.reset();  // patch indices of the old level
        upload_level();
        solver_ = std::make_unique<ProgressiveSolver>(scene(), levels_.provider(), solver_options_);
        reset_plot();
        info("viewer: level {}: {} elements in {} patches", levels_.level(), scene().size(), start_patches_);
    }

    bool solving() const { return !paused_ && solver_->status() == StopReason::Running; }

    void step(const StepBudget& budget) {
        Stopwatch watch;
        solver_->step(budget);
        record_step(watch.seconds());
    }

    void record_step(double seconds) {
        solver_seconds_ += seconds;
        plot_.add(solver_seconds_, solver_->unshot_fraction());
        const double now = glfwGetTime();
        rate_window_.push_back({now, solver_->shots()});
        while (rate_window_.size() > 2 && now - rate_window_.front().first > 1.0) rate_window_.pop_front();
    }

    double shots_per_second() const {
        if (rate_window_.size() < 2 || !solving()) return 0.0;
        const double dt = rate_window_.back().first - rate_window_.front().first;
        return dt > 0.0 ? static_cast<double>(rate_window_.back().second - rate_window_.front().second) / dt : 0.0;
    }

    // See run_viewer: the average radiosity to expect maps to 0.5 before tone mapping.
    double default_exposure() const {
        Vec3 rho(0.0);
        for (const Patch& p : scene().patches) rho += p.area * scene().materials[p.material].kd;
        rho /= std::max(scene().total_area(), 1e-300);
        const Vec3 expected = rho * solver_->ambient();
        const double luminance = 0.2126 * expected.r + 0.7152 * expected.g + 0.0722 * expected.b;
        return luminance > 0.0 ? std::log2(0.5 / luminance) : 0.0;
    }

    std::vector<Vec3> displayed_radiosity() const {
        const auto b = solver_->radiosity();
        return ambient_ ? display_radiosity(scene(), b, solver_->ambient()) : std::vector<Vec3>(b.begin(), b.end());
    }

    const std::vector<float>& colors() {
        if (show_row()) {
            flat_colors(mesh_, inspected_->heat, colors_);
        } else {
            const std::vector<Vec3> b = displayed_radiosity();
            if (smooth_) smooth_colors(mesh_, scene(), b, colors_);
            else flat_colors(mesh_, b, colors_);
        }
        return colors_;
    }

    bool show_row() const { return inspected_ && row_mode_; }

    float aspect(int width, int height) const { return static_cast<float>(width) / static_cast<float>(std::max(height, 1)); }

    DrawSettings settings(int width, int height) const {
        DrawSettings s;
        s.view_projection = camera_.view_projection(aspect(width, height));
        s.radiance = !show_row();
        s.exposure = exposure_;
        s.tone_map = tone_map_;
        s.wireframe = wireframe_;
        s.obstructions = show_obstructions_;
        s.outline = inspected_ ? static_cast<std::int64_t>(inspected_->patch) : -1;
        return s;
    }

    void handle_input() {
        const ImGuiIO& io = ImGui::GetIO();
        if (!io.WantCaptureMouse) {
            const bool pan_drag = ImGui::IsMouseDragging(ImGuiMouseButton_Right) || ImGui::IsMouseDragging(ImGuiMouseButton_Middle) ||
                                  (ImGui::IsMouseDragging(ImGuiMouseButton_Left) && io.KeyShift);
            int width = 0, height = 0;
            glfwGetWindowSize(window_.window(), &width, &height);
            if (pan_drag) camera_.pan(io.MouseDelta.x, io.MouseDelta.y, height);
            else if (ImGui::IsMouseDragging(ImGuiMouseButton_Left)) camera_.orbit(io.MouseDelta.x, io.MouseDelta.y);
            if (io.MouseWheel != 0.0f) camera_.zoom(io.MouseWheel);
            // A click is a press and release that hardly moved (3 pixels): a drag orbits instead.
            if (ImGui::IsMouseReleased(ImGuiMouseButton_Left) && io.MouseDragMaxDistanceSqr[0] < 9.0f)
                pick_window_pixel(static_cast<int>(io.MousePos.x), static_cast<int>(io.MousePos.y));
        }
        if (io.WantCaptureKeyboard) return;
        if (ImGui::IsKeyPressed(GLFW_KEY_SPACE, false)) paused_ = !paused_;
        if (ImGui::IsKeyPressed(GLFW_KEY_N)) single_step();
        if (ImGui::IsKeyPressed(GLFW_KEY_R, false)) reset();
        if (ImGui::IsKeyPressed(GLFW_KEY_P, false)) save_png_ = next_file_name("png");
        if (ImGui::IsKeyPressed(GLFW_KEY_E, false)) save_exr_ = next_file_name("exr");
        if (ImGui::IsKeyPressed(GLFW_KEY_F, false)) smooth_ = !smooth_;
        if (ImGui::IsKeyPressed(GLFW_KEY_W, false)) wireframe_ = !wireframe_;
        if (ImGui::IsKeyPressed(GLFW_KEY_O, false)) show_obstructions_ = !show_obstructions_;
        if (ImGui::IsKeyPressed(GLFW_KEY_A, false)) ambient_ = !ambient_;
        if (ImGui::IsKeyPressed(GLFW_KEY_H, false)) show_ui_ = !show_ui_;
        if (ImGui::IsKeyPressed(GLFW_KEY_T, false)) tone_map_ = static_cast<ToneMap>((static_cast<int>(tone_map_) + 1) % 3);
        if (ImGui::IsKeyPressed(GLFW_KEY_C, false)) camera_ = OrbitCamera::frame(scene());
        if (ImGui::IsKeyPressed(GLFW_KEY_EQUAL) || ImGui::IsKeyPressed(GLFW_KEY_KP_ADD)) exposure_ += 0.25f;
        if (ImGui::IsKeyPressed(GLFW_KEY_MINUS) || ImGui::IsKeyPressed(GLFW_KEY_KP_SUBTRACT)) exposure_ -= 0.25f;
        if (ImGui::IsKeyPressed(GLFW_KEY_ESCAPE, false)) inspected_.reset();
        if (ImGui::IsKeyPressed(GLFW_KEY_Q, false)) glfwSetWindowShouldClose(window_.window(), GLFW_TRUE);
    }

    void single_step() {
        if (solver_->status() == StopReason::Running) step(StepBudget{1, INFINITY});
    }

    void reset() {
        solver_->reset();
        reset_plot();
    }

    void reset_plot() {
        plot_.clear();
        rate_window_.clear();
        solver_seconds_ = 0.0;
    }

    // (x, y): window coordinates from the top left, as the mouse reports them.
    void pick_window_pixel(int x, int y) {
        int width = 0, height = 0, fb_width = 0, fb_height = 0;
        glfwGetWindowSize(window_.window(), &width, &height);
        glfwGetFramebufferSize(window_.window(), &fb_width, &fb_height);
        if (width <= 0 || height <= 0 || fb_width <= 0 || fb_height <= 0) return;
        // Framebuffer pixels may be finer than window coordinates (HiDPI); GL rows run bottom-up.
        const int px = x * fb_width / width, py = fb_height - 1 - y * fb_height / height;
        const std::uint32_t item = renderer_->pick(camera_.view_projection(aspect(fb_width, fb_height)), fb_width, fb_height, px, py);
        if (item == 0) {
            inspected_.reset();
            return;
        }
        inspect(item - 1);
    }

    void inspect(std::uint32_t patch) {
        auto in = std::make_unique<Inspected>();
        in->patch = patch;
        const std::uint32_t rows[1] = {patch};
        levels_.provider().compute_rows(rows, [&](std::uint32_t, const SparseRow& row) { in->row = row; });
        in->heat = row_heat_map(scene(), patch, in->row);
        // The picture is the plain hemicube's item buffer (what the row was measured from); the
        // numbers are the row as the solver gets it (corrected when the correction is on).
        if (levels_.hemicube()) in->image.upload(window_.api(), levels_.hemicube()->item_buffer(patch), levels_.hemicube()->resolution());
        inspected_ = std::move(in);
        row_mode_ = true;
        info("picked patch {} ({}): {} form factors, row sum {:.9g}", patch, scene().objects[scene().patches[patch].object],
             inspected_->row.nnz(), inspected_->row.sum());
    }

    void write_screenshot(const std::string& path, int width, int height) {
        write_png_rgba8(path, width, height, read_back_buffer(window_.api(), width, height));
        status_ = "saved " + path;
        info("viewer: wrote {}", path);
    }

    // Linear radiance L = B/π as displayed (ambient and smoothing as set), without exposure or tone
    // map: the same convention as `ffcube solve --render X.exr` (docs/solve.md).
    void write_linear(const std::string& path, int width, int height) {
        std::vector<Vec3> b = displayed_radiosity();
        for (Vec3& v : b) v /= std::numbers::pi;
        std::vector<float> linear;
        if (smooth_) smooth_colors(mesh_, scene(), b, linear);
        else flat_colors(mesh_, b, linear);
        renderer_->set_colors(linear);
        write_exr(path, renderer_->render_linear(camera_.view_projection(aspect(width, height)), width, height));
        status_ = "saved " + path;
        info("viewer: wrote {}", path);
    }

    void draw_panels() {
        ImGui::SetNextWindowPos(ImVec2(8, 8), ImGuiCond_FirstUseEver);
        ImGui::Begin("ffcube view", nullptr, ImGuiWindowFlags_AlwaysAutoResize);
        ImGui::PushItemWidth(200);
        if (levels_.hemicube())
            ImGui::Text("%zu patches, hemicube %d px, %s", scene().size(), levels_.hemicube()->resolution(), levels_.hemicube()->backend().c_str());
        else
            ImGui::Text("%zu patches, rows by %s", scene().size(), levels_.provider().name().c_str());
        if (start_patches_ > 0)
            ImGui::Text("adaptive level %u%s: %zu elements in %zu patches (W: amber patches, blue elements)", levels_.level(),
                        levels_done_ ? " (last)" : "", scene().size(), start_patches_);
        ImGui::Text("shots %llu   unshot %.3e", static_cast<unsigned long long>(solver_->shots()), solver_->unshot_fraction());
        ImGui::Text("%.0f shots/s   %s", shots_per_second(),
                    solver_->status() == StopReason::Running ? (paused_ ? "paused" : "running")
                                                            : to_string(solver_->status()).c_str());
        plot_.draw();
        if (ImGui::Button(paused_ ? "resume" : "pause")) paused_ = !paused_;
        ImGui::SameLine();
        if (ImGui::Button("step")) single_step();
        ImGui::SameLine();
        if (ImGui::Button("reset")) reset();
        ImGui::SameLine();
        if (ImGui::Button("PNG")) save_png_ = next_file_name("png");
        ImGui::SameLine();
        if (ImGui::Button("EXR")) save_exr_ = next_file_name("exr");
        float budget = static_cast<float>(options_.budget_ms);
        if (ImGui::SliderFloat("ms/frame", &budget, 1.0f, 200.0f, "%.0f")) options_.budget_ms = budget;
        ImGui::SliderFloat("exposure", &exposure_, -10.0f, 10.0f, "%.2f EV");
        int tone = static_cast<int>(tone_map_);
        if (ImGui::Combo("tone map", &tone, "clamp\0Reinhard\0ACES\0")) tone_map_ = static_cast<ToneMap>(tone);
        ImGui::Checkbox("smooth", &smooth_);
        ImGui::SameLine();
        ImGui::Checkbox("ambient", &ambient_);
        ImGui::SameLine();
        ImGui::Checkbox("wireframe", &wireframe_);
        if (obstructions_.patches > 0) {
            ImGui::SameLine();
            ImGui::Checkbox("obstructions", &show_obstructions_);
        }
        if (!status_.empty()) ImGui::TextUnformatted(status_.c_str());
        ImGui::TextDisabled("drag: orbit, right/shift-drag: pan\nwheel: zoom, click: inspect a patch");
        ImGui::PopItemWidth();
        ImGui::End();
        if (inspected_) draw_inspector();
    }

    void draw_inspector() {
        const Inspected& in = *inspected_;
        const Patch& p = scene().patches[in.patch];
        const Material& m = scene().materials[p.material];
        const Vec3 b = solver_->radiosity()[in.patch];
        const Vec3 shown = ambient_ ? b + m.kd * solver_->ambient() : b;
        // Below the main panel (its height depends on the font; 330 px holds it at the default).
        ImGui::SetNextWindowPos(ImVec2(8, 330), ImGuiCond_FirstUseEver);
        ImGui::Begin("patch", nullptr, ImGuiWindowFlags_AlwaysAutoResize);
        ImGui::Text("patch %u of %s (%s), area %.4g", in.patch, scene().objects[p.object].c_str(), m.name.c_str(), p.area);
        ImGui::Text("B  %.4g %.4g %.4g", b.r, b.g, b.b);
        if (ambient_) ImGui::Text("B + rho*ambient  %.4g %.4g %.4g", shown.r, shown.g, shown.b);
        ImGui::Text("E  %.4g %.4g %.4g   rho %.3g %.3g %.3g", m.ke.r, m.ke.g, m.ke.b, m.kd.r, m.kd.g, m.kd.b);
        ImGui::Text("row: %zu form factors, sum %.5f", in.row.nnz(), in.row.sum());
        ImGui::Checkbox("row heat map (F_ij / A_j, log, 3 decades)", &row_mode_);
        const float w = 300.0f;
        if (levels_.hemicube()) {
            // The atlas's row 0 is at the bottom: flip v.
            ImGui::Image(reinterpret_cast<ImTextureID>(static_cast<std::intptr_t>(in.image.texture.id())),
                         ImVec2(w, w * static_cast<float>(in.image.height) / static_cast<float>(in.image.width)),
                         ImVec2(0, 1), ImVec2(1, 0));
            ImGui::TextDisabled("hemicube item buffer: five faces, one colour per patch");
        }
        // Closed after this frame is drawn: its draw list still refers to the hemicube texture.
        if (ImGui::Button("close (Esc)")) close_inspector_ = true;
        ImGui::End();
    }

    struct Inspected {
        std::uint32_t patch = 0;
        SparseRow row;
        std::vector<Vec3> heat;
        HemicubeImage image;
    };

    ViewerLevels& levels_;           // the scene, rows and hemicubes (null: not hemicubes) of the level shown
    SolverOptions solver_options_;
    ViewerOptions options_;
    std::unique_ptr<ProgressiveSolver> solver_;  // on the current level's scene and rows
    // GL objects below the window: destroyed first, while its context still exists.
    WindowContext window_;
    ImGuiSession imgui_;
    DisplayMesh mesh_;
    ObstructionMesh obstructions_;  // a .vs3's O surfaces (empty otherwise)
    std::optional<SceneRenderer> renderer_;  // refers to mesh_: rebuilt with it per level
    std::unique_ptr<Inspected> inspected_;

    OrbitCamera camera_;
    ToneMap tone_map_;
    float exposure_ = 0.0f;
    bool ambient_, smooth_, wireframe_, show_ui_, paused_;
    bool row_mode_ = false;
    bool show_obstructions_ = true;
    bool close_inspector_ = false;
    std::vector<float> colors_;
    ConvergencePlot plot_;
    double solver_seconds_ = 0.0;
    std::deque<std::pair<double, std::uint64_t>> rate_window_;
    std::string save_png_, save_exr_, status_;
    // Frames that shot: from the start of the first to the end of the last, and their shots.
    double shooting_start_ = 0.0, shooting_end_ = 0.0;
    std::uint64_t shots_while_shooting_ = 0;
    double draw_seconds_ = 0.0;  // the last frame's drawing, on this thread
    std::size_t start_patches_ = 0;  // patches of the adaptive start mesh; 0 when not adaptive
    bool levels_done_ = false;       // the last level's solve has stopped (ViewerLevels::finish said so)
    std::uint64_t earlier_shots_ = 0;  // shots of the levels before this one
};

}  // namespace

void validate(const ViewerOptions& o) {
    if (o.width < 64 || o.height < 64 || o.width > 16384 || o.height > 16384)
        throw InputError(fmt::format("--size {}x{}: width and height must be from 64 to 16384", o.width, o.height));
    if (!(o.budget_ms > 0.0) || !std::isfinite(o.budget_ms))
        throw InputError(fmt::format("--budget-ms {}: must be a positive number of milliseconds", o.budget_ms));
    if (o.exposure && !std::isfinite(*o.exposure)) throw InputError("--exposure: must be a finite number of stops");
    parse_tone_map(o.tone_map);
    if (o.frames < 0) throw InputError(fmt::format("--frames {}: must be ≥ 0", o.frames));
    if (o.frames > 0 && o.until_done) throw InputError("--frames and --until-done: give one of them");
    if (o.until_done && o.paused) throw InputError("--until-done with --paused: the solve would never end");
    if (o.frames == 0 && !o.until_done && (o.pick || !o.screenshot.empty() || !o.exr.empty()))
        throw InputError("--pick, --screenshot and --exr act after the last frame: give --frames N or --until-done");
    if (o.pick && (o.pick->first < 0 || o.pick->second < 0 || o.pick->first >= o.width || o.pick->second >= o.height))
        throw InputError(fmt::format("--pick {},{}: must lie inside the {}x{} window", o.pick->first, o.pick->second, o.width, o.height));
}

SolveResult run_viewer(ViewerLevels& levels, const SolverOptions& solver_options, const ViewerOptions& options) {
    validate(options);
    Viewer viewer(levels, solver_options, options);
    viewer.run();
    return viewer.result();
}

}  // namespace ffcube
