#include "ffcube/solver/solver.hpp"

#include <algorithm>
#include <cmath>

#include <fmt/format.h>

#include "ffcube/core/error.hpp"
#include "ffcube/core/log.hpp"
#include "ffcube/core/timer.hpp"
#include "ffcube/solver/progressive.hpp"
#include "internal.hpp"

namespace ffcube {
namespace {

constexpr const char* kChannel[3] = {"red", "green", "blue"};

bool finite(const Vec3& v) { return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z); }

}  // namespace

std::string to_string(SolverMethod m) {
    switch (m) {
        case SolverMethod::Shoot: return "shoot";
        case SolverMethod::Jacobi: return "jacobi";
        case SolverMethod::GaussSeidel: return "gauss-seidel";
        case SolverMethod::Direct: return "direct";
    }
    FFCUBE_CHECK_MSG(false, "unknown SolverMethod");
}

SolverMethod parse_solver_method(const std::string& name) {
    for (SolverMethod m : {SolverMethod::Shoot, SolverMethod::Jacobi, SolverMethod::GaussSeidel, SolverMethod::Direct})
        if (to_string(m) == name) return m;
    throw InputError(
        fmt::format("--solver '{}': unknown solver; use one of shoot, jacobi, gauss-seidel, direct", name));
}

void validate(const SolverOptions& o) {
    if (!(o.tolerance >= 0.0) || !std::isfinite(o.tolerance))
        throw InputError(fmt::format("--tolerance {}: must be a finite number ≥ 0 (a fraction of the emitted power)",
                                     o.tolerance));
    if (!(o.overshoot >= 1.0 && o.overshoot < 2.0))
        throw InputError(fmt::format(
            "--overshoot {}: the over-relaxation factor must lie in [1, 2); at 2 and above over-relaxed "
            "shooting no longer converges",
            o.overshoot));
    if (o.batch < 1) throw InputError("solver batch: must be at least 1 shooter per provider call");
    if (o.history_capacity < 2) throw InputError("solver history capacity: must keep at least 2 samples");
    if (!(o.row_cache_mb >= 0.0) || !(o.row_cache_mb <= 1e12))
        throw InputError(fmt::format("--row-cache-mb {}: must be a number of MiB in [0, 1e12]", o.row_cache_mb));
    if (o.blocks && o.method != SolverMethod::Jacobi && o.method != SolverMethod::GaussSeidel)
        throw InputError(fmt::format("--solver {}: only jacobi and gauss-seidel are split over several processes "
                                     "(mpirun); run {} in one process",
                                     to_string(o.method), to_string(o.method)));
    if (o.blocks && !(o.blocks->first() <= o.blocks->last()))
        throw InputError("solver row block: first row after last");
}

std::uint64_t effective_max_iterations(const SolverOptions& o, std::size_t patches) {
    if (o.max_iterations != 0) return o.max_iterations;
    if (o.method == SolverMethod::Shoot) return std::max<std::uint64_t>(100000, 1000 * std::uint64_t(patches));
    return 100000;
}

namespace detail {

std::string describe_patch(const Scene& scene, std::uint32_t i) {
    const Patch& p = scene.patches[i];
    const std::string object = p.object < scene.objects.size() ? scene.objects[p.object] : "?";
    const std::string material = p.material < scene.materials.size() ? scene.materials[p.material].name : "?";
    return fmt::format("patch {} (object '{}', material '{}')", i, object, material);
}

PatchInputs load_patches(const Scene& scene, const RowProvider& provider) {
    const std::size_t n = scene.size();
    if (provider.size() != n)
        throw InputError(fmt::format("{}: the {} form factors describe {} patches but the scene has {}: rows must "
                                     "come from the same scene and meshing",
                                     scene.source, provider.name(), provider.size(), n));
    PatchInputs in;
    in.area.resize(n);
    in.inv_area.resize(n);
    in.rho.resize(n);
    in.emit.resize(n);
    Vec3 rho_area(0.0);
    for (std::uint32_t i = 0; i < n; ++i) {
        const Patch& p = scene.patches[i];
        if (p.object >= scene.objects.size() || p.material >= scene.materials.size())
            throw InputError(fmt::format("{}: patch {}: object {} or material {} out of range", scene.source, i,
                                         p.object, p.material));
        if (!(p.area > 0.0) || !std::isfinite(p.area))
            throw InputError(fmt::format("{}: {}: area {} is not a positive finite number", scene.source,
                                         describe_patch(scene, i), p.area));
        const Material& m = scene.materials[p.material];
        if (!finite(m.kd) || !finite(m.ke) || m.kd.x < 0 || m.kd.y < 0 || m.kd.z < 0 || m.ke.x < 0 || m.ke.y < 0 ||
            m.ke.z < 0)
            throw InputError(fmt::format("{}: material '{}': Kd ({}, {}, {}) and Ke ({}, {}, {}) must be finite "
                                         "and ≥ 0",
                                         scene.source, m.name, m.kd.x, m.kd.y, m.kd.z, m.ke.x, m.ke.y, m.ke.z));
        for (int c = 0; c < 3; ++c)
            if (m.kd[c] >= 1.0)
                throw InputError(fmt::format(
                    "{}: material '{}' (used by {}): Kd = ({}, {}, {}) has reflectance ≥ 1 in the {} channel. A "
                    "surface that reflects everything it receives never loses energy: in a closed scene "
                    "B = E + ρFB then has no steady state and radiosity grows without bound. ffcube refuses "
                    "ρ ≥ 1 in every scene, open ones included, because form-factor rows carry discretisation "
                    "error that can close a nearly closed region. Use Kd < 1 (real materials reflect at most "
                    "about 0.95).",
                    scene.source, m.name, describe_patch(scene, i), m.kd.x, m.kd.y, m.kd.z, kChannel[c]));
        in.area[i] = p.area;
        in.inv_area[i] = 1.0 / p.area;
        in.rho[i] = m.kd;
        in.emit[i] = m.ke;
        in.emitted += m.ke * p.area;
        in.total_area += p.area;
        rho_area += m.kd * p.area;
    }
    in.emitted_total = in.emitted.x + in.emitted.y + in.emitted.z;
    if (n > 0) in.mean_rho = rho_area / in.total_area;
    return in;
}

double check_row(const Scene& scene, const RowProvider& provider, std::uint32_t i, const SparseRow& row,
                 const Vec3& rho) {
    const std::size_t n = scene.size();
    double sum = 0.0;
    for (std::size_t k = 0; k < row.nnz(); ++k) {
        const double v = row.val[k];
        if (row.col[k] >= n || !(v >= 0.0) || !std::isfinite(v))
            throw InputError(fmt::format("{}: {} form factors, row of {}: entry F[{}][{}] = {} is not a finite "
                                         "value ≥ 0 in range",
                                         scene.source, provider.name(), describe_patch(scene, i), i, row.col[k], v));
        sum += v;
    }
    for (int c = 0; c < 3; ++c)
        if (rho[c] * sum >= 1.0)
            throw InputError(fmt::format(
                "{}: {}: reflectance ρ = {} ({} channel) times the sum of its form factors {} gives {} ≥ 1: the "
                "patch would send on at least as much energy as it receives, so energy is never lost and "
                "B = E + ρFB has no steady state. Row sums above 1 are discretisation error of the {} form "
                "factors (raise the resolution) or a material too close to ρ = 1 (lower Kd below 1/{}).",
                scene.source, describe_patch(scene, i), rho[c], kChannel[c], sum, rho[c] * sum, provider.name(),
                sum));
    return sum;
}

// The error bound (SolveResult::error_bound). Notation: B* the exact solution for the rows at hand,
// ΔB the unshot radiosity (shooting) or the residual r = E + ρFB − B (gathering, direct), U_c =
// Σ_i A_i |ΔB_ic| the unshot power, q = ρ_max × max(1, max row sum), A = Σ_i A_i.
//
// Shooting: the state satisfies B = E + K y, y = B − ΔB, and B* = E + K B*, so B* − B = K (B* − y) =
// K (B* − B) + K ΔB. In power variables (multiply by A_j) K becomes K' with K'_ji = ρ_j F_ij, whose
// column i sums to Σ_j ρ_j F_ij ≤ ρ_max × rowsum_i ≤ q: ‖K'‖₁ ≤ q. With e = A∘(B* − B):
// ‖e‖₁ ≤ q ‖e‖₁ + q U, so Σ_i A_i |B*_i − B_i| ≤ q/(1 − q) × U ≤ U/(1 − q). Physically: the unshot
// power U, reflected on and on, adds at most qU + q²U + … to the scene, and U/(1 − q) also counts
// U itself (the bound of the ambient term's reasoning, which adds U/(1 − ρ̄) spread evenly).
// Gathering: (I − ρF)(B* − B) = r, so e = A∘r + A∘ρF(B* − B), and with reciprocal rows
// (A_i F_ij = A_j F_ji) Σ_i A_i ρ_i |Σ_j F_ij x_j| ≤ ρ_max Σ_j A_j |x_j| rowsum_j ≤ q ‖A∘x‖₁, so again
// ‖e‖₁ ≤ U + q ‖e‖₁ ≤ U/(1 − q); hemicube rows are reciprocal to a few percent, the bound is then
// approximate to that degree.
// Either way the area-weighted mean of |B* − B| is at most U/((1 − q) A), reported per channel. Rows
// the solve never saw are assumed to sum to at most 1 (closed or open scene).
void set_error_bound(SolveResult& r, const PatchInputs& in) {
    r.error_bound = Vec3(0.0);
    r.error_bound_relative = 0.0;
    if (!(in.total_area > 0.0)) return;
    Vec3 mean_b(0.0);
    for (std::uint32_t i = 0; i < in.size(); ++i) mean_b += in.area[i] * r.radiosity[i];
    mean_b /= in.total_area;
    for (int c = 0; c < 3; ++c) {
        double rho_max = 0.0;
        for (const Vec3& rho : in.rho) rho_max = std::max(rho_max, rho[c]);
        const double q = rho_max * std::max(1.0, r.stiffness.max_row_sum);
        r.error_bound[c] = q < 1.0 ? r.unshot_abs[c] / ((1.0 - q) * in.total_area) : INFINITY;
        if (r.unshot_abs[c] == 0.0) r.error_bound[c] = 0.0;
        if (mean_b[c] > 0.0) r.error_bound_relative = std::max(r.error_bound_relative, r.error_bound[c] / mean_b[c]);
        else if (r.error_bound[c] > 0.0) r.error_bound_relative = INFINITY;
    }
}

SolveResult nothing_to_do(const Scene& scene, SolverMethod method) {
    SolveResult r;
    r.method = method;
    r.radiosity.assign(scene.size(), Vec3(0.0));
    r.stop = StopReason::NothingToDo;
    r.cache.patches_without_row = scene.size();
    r.warnings.push_back(fmt::format("{}: no patch emits light (every Ke is 0): radiosity is 0 everywhere",
                                     scene.source.empty() ? "scene" : scene.source));
    return r;
}

}  // namespace detail

SolveResult solve_radiosity(const Scene& scene, RowProvider& provider, const SolverOptions& options) {
    validate(options);
    const Stopwatch watch;
    SolveResult r;
    if (options.method == SolverMethod::Shoot) {
        r = detail::solve_shooting(scene, provider, options);
    } else if (options.method == SolverMethod::Direct) {
        r = detail::solve_direct(scene, provider, options);
    } else {
        r = detail::solve_sweeps(scene, provider, options);
    }
    r.timings.total = watch.seconds();
    if (r.stop != StopReason::NothingToDo) detail::set_error_bound(r, detail::load_patches(scene, provider));
    for (const std::string& w : r.warnings) log_warning(w);
    return r;
}

std::string describe_unconverged(const SolveResult& r, const SolverOptions& o) {
    const std::string what = r.stop == StopReason::Diverged ? "diverged" : "stopped at the iteration limit";
    std::string bound = std::isfinite(r.error_bound_relative)
                            ? fmt::format("{:.3g} of the mean radiosity", r.error_bound_relative)
                            : std::string("unbounded (ρ_max × row sum ≥ 1)");
    return fmt::format("the {} solve {} after {} {} without reaching its tolerance: unshot fraction {:.3e} > {:.1e}; "
                       "error bound on B: {}",
                       to_string(r.method), what, r.iterations,
                       r.method == SolverMethod::Shoot ? "shots" : (r.method == SolverMethod::Direct ? "solve" : "sweeps"),
                       r.unshot_fraction, o.tolerance, bound);
}

void require_converged(const SolveResult& r, const SolverOptions& o, bool allow_unconverged) {
    if (r.converged()) return;
    if (allow_unconverged && r.stop != StopReason::Diverged) return;
    throw NotConvergedError(describe_unconverged(r, o) +
                            (r.stop == StopReason::Diverged ? "" : " (--allow-unconverged writes it anyway)"));
}

std::vector<ObjectRadiosity> object_radiosity(const Scene& scene, std::span<const Vec3> radiosity) {
    FFCUBE_CHECK(radiosity.size() == scene.size());
    std::vector<ObjectRadiosity> out(scene.objects.size());
    for (std::size_t o = 0; o < out.size(); ++o) out[o].name = scene.objects[o];
    for (std::size_t i = 0; i < scene.size(); ++i) {
        const Patch& p = scene.patches[i];
        FFCUBE_CHECK(p.object < out.size());
        out[p.object].area += p.area;
        out[p.object].radiosity += radiosity[i] * p.area;
    }
    for (ObjectRadiosity& o : out)
        if (o.area > 0.0) o.radiosity /= o.area;
    return out;
}

std::vector<Vec3> display_radiosity(const Scene& scene, std::span<const Vec3> radiosity, const Vec3& ambient) {
    FFCUBE_CHECK(radiosity.size() == scene.size());
    std::vector<Vec3> out(radiosity.begin(), radiosity.end());
    for (std::size_t i = 0; i < out.size(); ++i) {
        const Patch& p = scene.patches[i];
        FFCUBE_CHECK(p.material < scene.materials.size());
        out[i] += scene.materials[p.material].kd * ambient;
    }
    return out;
}

}  // namespace ffcube
