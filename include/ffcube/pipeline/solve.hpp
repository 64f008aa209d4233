// Radiosity solves as every front end runs them (the command line's `solve`, the Python module's
// ffcube.solve): the same shot batch, the same progress lines, the same report keys.
#pragma once

#include <cstddef>
#include <cstdint>
#include <optional>
#include <string_view>

#include "ffcube/formfactor/row_provider.hpp"
#include "ffcube/io/report.hpp"
#include "ffcube/scene/scene.hpp"
#include "ffcube/solver/solver.hpp"

namespace ffcube {

// Shooters asked from the row provider per call (SolverOptions::batch) by solve and the viewer:
// enough to keep 16 hemicube workers busy (the viewer once asked one per worker, and its workers
// idled between batches: docs/benchmarks.md). Fixed rather than the thread count, because the shooting order (and so B
// in its last digits) depends on the batch, and results must not depend on the thread count.
inline constexpr std::uint32_t kShotBatch = 16;

// --overshoot's value: empty (the option given alone) is kDefaultOvershoot; otherwise the whole
// text must be a number (InputError naming it). Range checks are validate(SolverOptions)'s.
double parse_overshoot(std::string_view text);

// Solves B = E + ρ F B with options.batch = kShotBatch (whatever the caller set), printing
// progress about once a second and a summary line (core/log.hpp), and records the result in the
// report (solver.*, iterations, energy.*, stiffness.*, row_cache.*, history.*, time.*). Does not
// throw for an unconverged solve: see require_converged.
SolveResult solve_and_report(const Scene& scene, RowProvider& rows, SolverOptions options, Report& report);

// The two halves of solve_and_report, for front ends that run the solve themselves (adaptive
// meshing's levels): options with the shot batch and the progress lines, and the summary lines
// and report keys of a finished solve.
SolverOptions front_end_solver_options(SolverOptions options);
void report_solve(const Scene& scene, const SolveResult& result, const SolverOptions& options, Report& report);

// The solver's ETA, from the measured decay of the unshot power (or the residual): between two
// progress samples (t0, f0) and (t1, f1), t1 > t0, the fraction is taken to decay exponentially at
// the rate measured, r = ln(f0/f1)/(t1 − t0), so it reaches the tolerance after ln(f1/tol)/r more
// seconds. nullopt when there is no decay to measure (f1 ≥ f0, a zero or non-finite value, or
// t1 ≤ t0); 0 when f1 is already at or under the tolerance.
std::optional<double> solve_eta_seconds(double t0, double f0, double t1, double f1, double tolerance);

// An RGB value as a three-number array at key.
void report_vec3(Report& report, std::string_view key, const Vec3& value);

}  // namespace ffcube
