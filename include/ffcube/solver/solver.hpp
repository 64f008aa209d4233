// Radiosity solvers on a RowProvider: B = E + ρ F B per RGB channel, accumulated in double.
//   B_i: radiosity of patch i (power leaving per unit area, the units of Ke);
//   E_i: emitted radiosity (the material's Ke); ρ_i: diffuse reflectance (Kd), each channel in [0,1);
//   F[i][j]: fraction of the energy leaving i that arrives at j (see formfactor/sparse.hpp).
// Methods, options, the stiffness rule and the stopping rules are described in docs/solvers.md.
// The solver never sees GL; it asks the provider for rows and, for shooting, only for the rows of
// patches that actually shoot.
#pragma once

#include <cstddef>
#include <cstdint>
#include <functional>
#include <span>
#include <string>
#include <vector>

#include "ffcube/formfactor/row_provider.hpp"
#include "ffcube/scene/scene.hpp"
#include "ffcube/solver/convergence.hpp"
#include "ffcube/solver/row_blocks.hpp"

namespace ffcube {

enum class SolverMethod { Shoot, Jacobi, GaussSeidel, Direct };
// "shoot", "jacobi", "gauss-seidel", "direct".
std::string to_string(SolverMethod m);
// Inverse of to_string; InputError naming the accepted values otherwise.
SolverMethod parse_solver_method(const std::string& name);

// The direct solve stores (I − ρF) densely, N² doubles per channel (N = 4000: 128 MB), and LU
// costs (2/3)·N³ flops per channel (N = 4000: 4.3·10¹⁰, about a minute per channel on one core
// without a tuned BLAS); above this size it is refused in favour of shooting or Gauss–Seidel.
inline constexpr std::uint32_t kDirectMaxPatches = 4000;

// The over-relaxation factor ω that `--overshoot` without a value means (docs/solvers.md).
inline constexpr double kDefaultOvershoot = 1.2;

// What the progress callback sees: after every batch of shots (every shot with the default
// batch = 1), after every sweep (jacobi, gauss-seidel), once at the end (direct).
struct SolveProgress {
    SolverMethod method = SolverMethod::Shoot;
    std::uint64_t iterations = 0;  // shots or sweeps so far
    double unshot_fraction = 1.0;  // unshot (residual) power / emitted power
    double seconds = 0.0;          // since the solve started
};

struct SolverOptions {
    SolverMethod method = SolverMethod::Shoot;
    // Stop when unshot power ≤ tolerance × emitted power (power summed over RGB). ≥ 0.
    double tolerance = 1e-4;
    // Shots (shoot) or sweeps (jacobi, gauss-seidel); 0 = the method's default
    // (effective_max_iterations). Ignored by direct.
    std::uint64_t max_iterations = 0;
    // Over-relaxation factor ω of progressive refinement, in [1, 2): each shot sends ω times the
    // patch's unshot radiosity, leaving it (1 − ω) times that (negative: shot later). 1 = Cohen's
    // classic shooting. Ignored by the other methods.
    double overshoot = 1.0;
    // Bound of the LRU cache of shooters' rows, in MiB (2^20 bytes; fractions allowed); 0 = no
    // cache (every shot asks the provider). Rows are kept in double, 12 bytes per non-zero plus a
    // small header (RowCache::cost).
    double row_cache_mb = 512.0;
    // Shooters asked from the provider in one compute_rows call (lets a parallel provider work).
    // ≥ 1. Results depend on it (the shooting order does) but are deterministic for a given value.
    std::uint32_t batch = 1;
    // Most samples kept in SolveResult::history (≥ 2).
    std::size_t history_capacity = 1024;
    // Called on the solving thread as SolveProgress says; may be empty. Seconds count time spent
    // solving (inside step() for the stepping API), not time between steps.
    std::function<void(const SolveProgress&)> progress;
    // shoot through solve_radiosity only: when the measured decay of the unshot power predicts more
    // than 300 × N further shots, or more than the shot limit, finish with GMRES on the rows
    // (docs/solvers.md, "Stiff scenes"). false: plain shooting to the end (the stepping API, tests
    // of shooting itself).
    bool stiff_switch = true;
    // jacobi and gauss-seidel only: solve this process's block of rows, sharing B with the
    // other blocks after each sweep (solver/row_blocks.hpp; `mpirun … ffcube solve`). Every block
    // returns the whole B. nullptr: one process, every row.
    RowBlocks* blocks = nullptr;
};

// InputError naming the option and the rule when an option is out of range.
void validate(const SolverOptions& options);
// max_iterations, or when 0: shoot 1000·N shots (at least 100000), sweeps 100000.
std::uint64_t effective_max_iterations(const SolverOptions& options, std::size_t patches);

// Energy bookkeeping, power per RGB channel (Ke units × area units²).
//   emitted  = Σ_i E_i A_i
//   absorbed = Σ over everything received of (1 − ρ_j) × the power arriving at j
//   escaped  = Σ over shots of (1 − rowsum_i) × the power shot (through openings; negative when a
//              row sums above 1 through discretisation error)
//   unshot   = Σ_i ΔB_i A_i (signed: overshooting leaves negative unshot radiosity), which includes
//              the reflected power still "in flight".
// emitted = absorbed + escaped + unshot holds exactly in real arithmetic at every shot.
struct EnergyBalance {
    Vec3 emitted{0.0}, absorbed{0.0}, escaped{0.0}, unshot{0.0};
    // max over channels of |emitted − absorbed − escaped − unshot| / turnover, where turnover is
    // emitted + all power ever shot in that channel: the scale of the rounding error.
    double relative_error = 0.0;
};

struct RowCacheStats {
    std::uint64_t rows_computed = 0;      // rows asked from the provider (including recomputations)
    std::uint64_t rows_reused = 0;        // shots served from the cache
    std::uint64_t rows_evicted = 0;       // rows dropped to stay within the bound
    std::uint64_t rows_recomputed = 0;    // rows computed again after an eviction (or no cache)
    std::uint64_t patches_without_row = 0;  // patches whose row was never needed
    std::size_t capacity_bytes = 0;
    std::size_t peak_bytes = 0;
};

struct SolveTimings {
    double total = 0.0;  // seconds, the whole solve
    double rows = 0.0;   // seconds inside the row provider
    double solve = 0.0;  // seconds shooting, sweeping or factorising
};

// What the default solve found out about stiffness and did about it (docs/solvers.md, "Stiff
// scenes"). Filled by shoot; the gathering methods fill rho_max and max_row_sum.
struct StiffnessReport {
    double rho_max = 0.0;      // largest reflectance of any patch, any channel
    double max_row_sum = 0.0;  // largest sum of the rows the solve saw
    // A priori: generations (every patch shooting once) plain shooting needs in a closed scene,
    // ln τ / ln ρ_max (0 when not meaningful).
    double predicted_generations = 0.0;
    // Measured: unshot fraction at the end of the last window of plain shooting over its value at the
    // start, the window's shots, and the shots plain shooting would need in all at that decay rate.
    double decay_per_window = 0.0;
    std::uint64_t window_shots = 0;
    double predicted_shots = 0.0;
    bool stiff = false;             // the decay was too slow for plain shooting
    std::string action = "none";    // "none", "gmres", "gmres (rejected)"
    std::string reason;             // why, in words (empty when nothing was done)
    std::uint64_t switched_at_shot = 0;
    std::uint64_t krylov_products = 0;       // products with the rows in the GMRES finish (all channels)
    std::uint64_t finish_rows_computed = 0;  // rows the finish asked from the provider
};

struct SolveResult {
    SolverMethod method = SolverMethod::Shoot;
    std::vector<Vec3> radiosity;  // B per patch, RGB; the ambient term is never added in
    // Cohen's ambient radiosity (shoot only, else 0): for display add ρ_i × ambient to B_i
    // (display_radiosity). Signed: negative while overshooting has sent more than was due.
    Vec3 ambient{0.0};
    std::uint64_t iterations = 0;  // shots (shoot), sweeps (jacobi, gauss-seidel), 1 (direct)
    std::uint64_t shots = 0;       // shots (shoot only)
    double unshot_fraction = 0.0;  // unshot (or residual) power / emitted power at the end
    StopReason stop = StopReason::Running;
    EnergyBalance energy;
    SolveTimings timings;
    std::vector<ConvergenceSample> history;  // sampled, at most options.history_capacity
    RowCacheStats cache;                     // shoot only
    std::vector<std::string> warnings;       // solve_radiosity also prints them with log_warning
    StiffnessReport stiffness;
    // Per channel Σ_i A_i |ΔB_i| (shoot) or Σ_i A_i |r_i| (gathering, direct): the unshot power.
    Vec3 unshot_abs{0.0};
    // Bound on the area-weighted mean of |B* − B| per channel, B* the exact solution for the rows at
    // hand: unshot_abs / ((1 − q) Σ A), q = ρ_max × max(1, max_row_sum) (derivation in
    // docs/solvers.md and solver.cpp; exact for shooting, for gathering when rows are reciprocal).
    // Infinite when q ≥ 1. error_bound_relative: the largest bound over the area-weighted mean B
    // of its channel.
    Vec3 error_bound{0.0};
    double error_bound_relative = 0.0;
    // radiosity never includes Cohen's ambient term (display_radiosity adds it for display).
    bool ambient_included = false;

    // stop is converged or nothing_to_do.
    bool converged() const { return stop == StopReason::Converged || stop == StopReason::NothingToDo; }
};

// Solves with options.method. Throws InputError when the scene or the rows break the stiffness
// rule (a reflectance ≥ 1 in some channel, or ρ_i × rowsum_i ≥ 1: docs/solvers.md), when the
// provider's size differs from the scene's, for invalid options, and for direct above
// kDirectMaxPatches. The provider must describe the scene's patches in the scene's order.
SolveResult solve_radiosity(const Scene& scene, RowProvider& provider, const SolverOptions& options);

// "stopped at the iteration limit after ... : unshot fraction ... > tolerance ..., error bound ...":
// what a caller says when it refuses an unconverged result.
std::string describe_unconverged(const SolveResult& result, const SolverOptions& options);
// Throws NotConvergedError (exit code 5) with describe_unconverged unless result.converged(), or
// allow_unconverged and the solve did not diverge (a diverged B is never a usable answer).
void require_converged(const SolveResult& result, const SolverOptions& options, bool allow_unconverged);

// Area-weighted mean radiosity per object: Σ_{i∈o} A_i B_i / Σ_{i∈o} A_i (0 for an object with no
// patches), in Scene::objects order.
struct ObjectRadiosity {
    std::string name;
    double area = 0.0;
    Vec3 radiosity{0.0};
};
std::vector<ObjectRadiosity> object_radiosity(const Scene& scene, std::span<const Vec3> radiosity);

// B_i + ρ_i × ambient: what a viewer shows while shooting is unfinished.
std::vector<Vec3> display_radiosity(const Scene& scene, std::span<const Vec3> radiosity, const Vec3& ambient);

}  // namespace ffcube
