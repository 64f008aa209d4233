// Adaptive meshing (issue 16, docs/adaptive.md): solve, estimate where the radiosity varies, split
// those patches into elements, solve again on the refined scene, until the estimated error of every
// object's radiosity is below a target or an element budget is spent.
//
// Each level is an ordinary solve (solver/solver.hpp) of the refined scene with rows from
// make_row_source: a refined patch's elements are receivers (one hemicube or ray-cast row each)
// and shooters; the patches left alone keep their coarse rows. Why elements shoot too rather than
// only gather (Cohen's substructuring) is argued in docs/adaptive.md.
#pragma once

#include <cstdint>
#include <functional>
#include <memory>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "ffcube/io/report.hpp"
#include "ffcube/pipeline/options.hpp"
#include "ffcube/pipeline/row_source.hpp"
#include "ffcube/scene/scene.hpp"
#include "ffcube/solver/solver.hpp"

namespace ffcube {

struct AdaptiveOptions {
    // Stop when every object's estimated relative discretisation error is at most this (> 0).
    double target_error = 1e-3;
    // Most elements (patches of the refined scene); ≥ the starting scene's patches.
    std::size_t max_elements = 8000;
    // Most refinement levels after the first solve (≥ 1).
    std::uint32_t max_levels = 4;
    // Each refined patch becomes factor × factor elements (2..8).
    std::uint32_t factor = 2;
    // Each level splits the patches that hold this fraction of the estimated misplaced power
    // (choose_refinement), in (0, 1].
    double fraction = 0.5;
    // Carry the rows of patches not split over to the next level (docs/adaptive.md, "Rows reused
    // between levels"); off (tests only): every level measures every row.
    bool reuse_rows = true;
    // Keep the first level's row source (its forked hemicube workers) for every level and send
    // it each level's elements (rebind_row_source); off: a new row source, and new workers, per
    // level (tests only). The rows are the same bits either way (tested).
    bool keep_workers = true;
};

// The starting mesh of an adaptive solve when the command line names none: coarse enough that the
// refinement pays for itself (docs/adaptive.md, measured).
inline constexpr std::size_t kAdaptiveStartPatches = 500;

void validate(const AdaptiveOptions& options);

struct AdaptiveLevel {
    std::size_t elements = 0;       // patches of this level's scene
    std::size_t refined = 0;        // patches split to make the next level (0 for the last)
    std::size_t candidates = 0;     // patches whose variation exceeded the target
    std::uint64_t rows_computed = 0;  // rows measured (hemicubes or ray sets)
    std::uint64_t rows_reused = 0;    // rows carried over from the previous level
    double seconds = 0.0;           // rows and solve of this level
    double setup_seconds = 0.0;     // of which: starting (or re-pointing) the row source
    std::vector<Vec3> objects;      // area-weighted mean B per object
};

struct ObjectError {
    std::string name;
    Vec3 radiosity{0.0};
    Vec3 error{0.0};      // estimated |B − B_converged| per channel
    double relative = 0;  // max channel error / max channel radiosity (0 for an unlit object)
};

struct AdaptiveResult {
    // The last level's scene (elements), on the heap: `rows` refers to it, and a result that is
    // moved (returned, assigned into an optional) must not leave the rows pointing at a moved-from scene.
    std::unique_ptr<Scene> scene;
    std::vector<std::uint32_t> origin;  // element → patch of the starting scene
    SolveResult result;                 // the last level's solve
    RowSource rows;                     // the last level's rows (for report_row_source), still running
    std::vector<AdaptiveLevel> levels;
    std::vector<ObjectError> objects;
    // "levels": error = |B_last − B_previous| (2/φ − 1), φ the share of the object's area split
    // (object_errors_between_levels; docs/adaptive.md);
    // "variation": one level only, error = area-weighted mean of the patches' variation.
    std::string error_basis;
    // "target", "nothing_to_refine", "element_budget", "level_limit", or "unconverged_solve".
    std::string stop;
    bool reached_target = false;
    double max_relative_error = 0.0;
};

// Solves `start` adaptively. Throws what solve_radiosity and make_row_source throw; a level whose
// solve does not converge ends the refinement (stop "unconverged_solve", result as the solver left it).
// progress (may be empty) gets one line per level.
AdaptiveResult solve_adaptive(const Scene& start, const RowOptions& rows, const SolverOptions& solver,
                              const AdaptiveOptions& options, const std::function<void(const std::string&)>& progress = {});

// An adaptive solve held between levels, for a caller that runs each level's solve itself (the
// viewer, docs/viewer.md) or lets it run solve_radiosity (step_level; solve_adaptive is a loop of it).
// A level is: scene() and provider() (its rows, reused from the previous level where unsplit), solved
// by the caller; finish_level(result) then estimates the errors and chooses the refinement, or ends
// the run (done()); next_level() installs the refined scene and its provider (the same forked
// hemicube workers, re-pointed at the new elements, unless keep_workers is off). Until next_level the
// current scene and provider stay as they were (a viewer keeps showing the last level's solve);
// scene() is the same object for every level, its content replaced by next_level, and provider() a
// new object: a solver on the old ones must be destroyed before next_level.
class AdaptiveRun {
public:
    // Validates as solve_adaptive does and starts level 0 (its row source, so its workers fork now).
    AdaptiveRun(const Scene& start, const RowOptions& rows, const SolverOptions& solver, const AdaptiveOptions& options,
                std::function<void(const std::string&)> progress = {});
    ~AdaptiveRun();
    AdaptiveRun(const AdaptiveRun&) = delete;
    AdaptiveRun& operator=(const AdaptiveRun&) = delete;

    std::uint32_t level() const;
    const Scene& scene() const;
    RowProvider& provider();
    HemicubeRowProvider* hemicube();  // the measuring hemicubes (null for ray-cast rows)
    std::span<const std::uint32_t> origin() const;  // element → patch of the starting scene
    const RowSource& rows() const;

    // Solves the current level with solve_radiosity and the solver options given, finish_level,
    // and next_level unless the run is done.
    void step_level();
    // Ends the current level with its solve (by any solver on scene() and provider()): records it,
    // estimates, and either ends the run (done()) or chooses the next level's elements.
    void finish_level(const SolveResult& result);
    // After a finish_level that did not end the run: the refined scene and its provider.
    void next_level();
    bool done() const;
    // The result as solve_adaptive returns it (after done(); the run is spent).
    AdaptiveResult take_result();

private:
    struct Impl;
    std::unique_ptr<Impl> impl_;
};

// Per-object errors from two levels' object radiosity. refined[o] is the share of object o's area
// that the last refinement split. Under first-order convergence (docs/adaptive.md, "The estimated
// error") splitting a share φ of an object, with its error spread evenly over its area, halves the
// error there: the levels differ by φ e/2 of the coarse error e, which leaves e − φ e/2, i.e.
// |ΔB| (2/φ − 1). An object with φ = 0 keeps its previous estimate (its mesh did not change).
std::vector<ObjectError> object_errors_between_levels(const Scene& scene, std::span<const Vec3> fine_objects,
                                                      std::span<const Vec3> coarse_objects, std::span<const double> refined,
                                                      std::span<const ObjectError> previous);

// One solve's per-object error estimate from its variation (error_basis "variation"): what a
// uniform solve reports.
std::vector<ObjectError> estimate_object_errors(const Scene& scene, std::span<const Vec3> radiosity);
// The report's "discretisation_error.*" keys.
void report_object_errors(Report& report, std::span<const ObjectError> objects, std::string_view basis, double max_relative);

// The report's "adaptive.*" and "discretisation_error.*" keys (docs/adaptive.md).
void report_adaptive(Report& report, const AdaptiveResult& adaptive, const AdaptiveOptions& options);

}  // namespace ffcube
