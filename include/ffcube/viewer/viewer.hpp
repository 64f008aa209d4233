// ffcube view: a window in which progressive refinement runs live. Each frame shoots for a time
// budget, then draws the current radiosity; the camera, display settings and patch inspection
// work at any moment (radiosity does not depend on the view). Controls: docs/viewer.md.
#pragma once

#include <cstdint>
#include <optional>
#include <span>
#include <string>

#include "ffcube/gl/hemicube_provider.hpp"
#include "ffcube/scene/scene.hpp"
#include "ffcube/solver/solver.hpp"

namespace ffcube {

struct ViewerOptions {
    int width = 1280, height = 800;    // window size, screen coordinates
    double budget_ms = 20.0;           // solver time per frame (at least one batch of shots)
    std::uint64_t shots_per_frame = 0; // at most this many shots per frame; 0 = as the budget allows
    std::optional<double> exposure;    // stops; unset: chosen from the scene (see run_viewer)
    std::string tone_map = "reinhard"; // "clamp", "reinhard" or "aces"
    bool ambient = true;               // add Cohen's ambient term ρ_i × ambient to the display
    bool flat = false;                 // flat patch shading instead of smooth (vertex-interpolated)
    bool wireframe = false;            // patch outlines
    bool hide_ui = false;              // start with the Dear ImGui panel hidden
    bool paused = false;               // start with the solver paused

    // Automation: frames > 0 runs that many frames, then picks (pick: window pixel x, y from the
    // top left), then writes the screenshot and/or EXR of the final frame, and returns.
    int frames = 0;
    // Automation: run frames until the last level's solve has stopped (the adaptive levels one after
    // the other), then act as after --frames.
    bool until_done = false;
    std::optional<std::pair<int, int>> pick;
    std::string screenshot;  // PNG of the window (with the panel unless hidden)
    std::string exr;         // linear radiosity of the current view (no exposure, tone map or panel)
};

// InputError naming the option when a value is out of range (before any window opens).
void validate(const ViewerOptions& options);

// Opens the window (an OpenGL 4.5 core context through GLFW) and runs until it is closed, or for
// options.frames frames. The rows come from `rows` (pipeline/row_source.hpp's provider, so the
// viewer gets the same rows as `ffcube solve` for the same options); `hemicube`, when not null, is
// the measuring provider, whose item buffer the patch inspector shows. Both should have been
// created before (so that hemicube workers could be forked while this process had no GL context);
// the solver steps on them from this thread.
// Exposure by default: 2^exposure × ρ̄ × ambient₀ = 0.5, ambient₀ being Cohen's ambient radiosity
// before any shot (the emitted power spread over the scene and all its bounces: the average
// radiosity to expect). Throws GlError when no window can be opened, InputError for bad options,
// IoError when a file cannot be written.
// origin (empty, or one per patch): after adaptive meshing, the patch of the starting mesh each
// patch of `scene` (an element) lies in (AdaptiveResult::origin); the wireframe then draws the
// starting patches' outlines and the element edges inside them in two colours (display.hpp).
// Returns the solve shown last (the last level's, as it stands when the window closes).
SolveResult run_viewer(const Scene& scene, RowProvider& rows, HemicubeRowProvider* hemicube, const SolverOptions& solver_options,
                       const ViewerOptions& options, std::span<const std::uint32_t> origin = {});

// What the viewer shows, level by level (adaptive meshing: cli/cmd_view.cpp drives AdaptiveRun
// through it). The viewer solves each level on scene() and provider() by progressive shooting; when
// that solve stops it calls finish(result). false: that was the last level, which stays on screen.
// true: the viewer destroys its solver (it refers to this level's scene and rows), calls advance(),
// and shows the new scene(), provider(), hemicube() and origin() with a new solver, mesh and buffers.
class ViewerLevels {
public:
    virtual ~ViewerLevels() = default;
    virtual const Scene& scene() const = 0;
    virtual RowProvider& provider() = 0;
    virtual HemicubeRowProvider* hemicube() = 0;  // null when the rows are not hemicubes
    // Empty, or per patch of scene() its patch of the starting mesh (see run_viewer's origin).
    virtual std::span<const std::uint32_t> origin() const = 0;
    virtual std::uint32_t level() const = 0;
    virtual bool finish(const SolveResult& result) = 0;
    virtual void advance() = 0;
};

// As above, the levels one after the other (until_done waits for the last).
SolveResult run_viewer(ViewerLevels& levels, const SolverOptions& solver_options, const ViewerOptions& options);

}  // namespace ffcube
