// Radiosity solves as every front end runs them: see ffcube/pipeline/solve.hpp.
#include "ffcube/pipeline/solve.hpp"

#include <memory>

#include <fmt/format.h>

#include <array>
#include <cmath>
#include <cstdlib>
#include <optional>
#include <string_view>
#include <string>
#include <vector>

#include "ffcube/core/error.hpp"
#include "ffcube/core/log.hpp"

namespace ffcube {

void report_vec3(Report& r, std::string_view key, const Vec3& v) {
    const std::array<double, 3> a{v.r, v.g, v.b};
    r.set_array(key, a);
}

namespace {

void report_result(Report& r, const SolveResult& res, const SolverOptions& so, std::size_t patches) {
    r.set("solver.method", to_string(res.method));
    r.set("solver.tolerance", so.tolerance);
    r.set("solver.max_iterations", effective_max_iterations(so, patches));
    r.set("solver.overshoot", so.overshoot);
    r.set("solver.row_cache_mb", so.row_cache_mb);
    r.set("solver.batch", so.batch);
    r.set("iterations", res.iterations);
    r.set("shots", res.shots);
    r.set("unshot_fraction", res.unshot_fraction);
    r.set("stop_reason", to_string(res.stop));
    r.set("converged", res.converged());
    report_vec3(r, "error_bound.mean_abs", res.error_bound);
    r.set("error_bound.relative", res.error_bound_relative);
    r.set("ambient_included", res.ambient_included);
    const StiffnessReport& st = res.stiffness;
    r.set("stiffness.rho_max", st.rho_max);
    r.set("stiffness.max_row_sum", st.max_row_sum);
    r.set("stiffness.predicted_generations", st.predicted_generations);
    r.set("stiffness.decay_per_window", st.decay_per_window);
    r.set("stiffness.window_shots", st.window_shots);
    r.set("stiffness.predicted_shots", st.predicted_shots);
    r.set("stiffness.stiff", st.stiff);
    r.set("stiffness.action", st.action);
    r.set("stiffness.reason", st.reason);
    r.set("stiffness.switched_at_shot", st.switched_at_shot);
    r.set("stiffness.krylov_products", st.krylov_products);
    r.set("stiffness.finish_rows_computed", st.finish_rows_computed);
    report_vec3(r, "energy.emitted", res.energy.emitted);
    report_vec3(r, "energy.absorbed", res.energy.absorbed);
    report_vec3(r, "energy.escaped", res.energy.escaped);
    report_vec3(r, "energy.unshot", res.energy.unshot);
    r.set("energy.relative_error", res.energy.relative_error);
    report_vec3(r, "ambient", res.ambient);
    r.set("time.solve_total", res.timings.total);
    r.set("time.rows", res.timings.rows);
    r.set("time.solving", res.timings.solve);
    std::vector<double> seconds, fraction;
    for (const ConvergenceSample& s : res.history) {
        seconds.push_back(s.seconds);
        fraction.push_back(s.unshot_fraction);
    }
    r.set_array("history.seconds", seconds);
    r.set_array("history.unshot_fraction", fraction);
    r.set("row_cache.rows_computed", res.cache.rows_computed);
    r.set("row_cache.rows_reused", res.cache.rows_reused);
    r.set("row_cache.rows_evicted", res.cache.rows_evicted);
    r.set("row_cache.rows_recomputed", res.cache.rows_recomputed);
    r.set("row_cache.patches_without_row", res.cache.patches_without_row);
    r.set("row_cache.capacity_bytes", res.cache.capacity_bytes);
    r.set("row_cache.peak_bytes", res.cache.peak_bytes);
    r.set_array("warnings", res.warnings);
}

}  // namespace

double parse_overshoot(std::string_view text) {
    if (text.empty()) return kDefaultOvershoot;
    const std::string s(text);
    std::size_t used = 0;
    double value = 0.0;
    try {
        value = std::stod(s, &used);
    } catch (const std::exception&) {
        used = 0;
    }
    if (used != s.size()) throw InputError(fmt::format("--overshoot {}: not a number", s));
    return value;
}

std::optional<double> solve_eta_seconds(double t0, double f0, double t1, double f1, double tolerance) {
    if (!(t1 > t0) || !std::isfinite(f0) || !std::isfinite(f1) || !(f1 > 0.0)) return std::nullopt;
    if (f1 <= tolerance) return 0.0;
    if (!(f0 > f1) || !(tolerance > 0.0)) return std::nullopt;
    const double rate = std::log(f0 / f1) / (t1 - t0);  // per second
    return std::log(f1 / tolerance) / rate;
}

SolverOptions front_end_solver_options(SolverOptions so) {
    so.batch = kShotBatch;
    // A line about once a second (every sample under FFCUBE_PROGRESS=always, for tests), with the
    // ETA from the decay since the previous line's sample.
    struct Last {
        double seconds = 0.0, fraction = NAN;
    };
    auto last = std::make_shared<Last>();
    const char* env = std::getenv("FFCUBE_PROGRESS");
    const bool always = env && std::string_view(env) == "always";
    so.progress = [last, always, tolerance = so.tolerance](const SolveProgress& p) {
        if (p.seconds < last->seconds) *last = Last{};  // a new solve (adaptive meshing's next level)
        if (!always && p.seconds - last->seconds < 1.0) return;
        const std::optional<double> eta = std::isnan(last->fraction)
                                              ? std::nullopt
                                              : solve_eta_seconds(last->seconds, last->fraction, p.seconds,
                                                                  p.unshot_fraction, tolerance);
        last->seconds = p.seconds;
        last->fraction = p.unshot_fraction;
        info("{}: {} {}, unshot {:.3e} of emitted (target {:.0e}), {:.1f} s, {}", to_string(p.method), p.iterations,
             p.method == SolverMethod::Shoot ? "shots" : "sweeps", p.unshot_fraction, tolerance, p.seconds,
             eta ? fmt::format("ETA {:.0f} s", *eta) : std::string("ETA not known yet"));
    };
    return so;
}

void report_solve(const Scene& scene, const SolveResult& res, const SolverOptions& so, Report& report) {
    info("{}: {} after {} {} ({} rows computed, {} reused), unshot {:.3e}, {:.2f} s", to_string(res.method),
         to_string(res.stop), res.iterations, res.method == SolverMethod::Shoot ? "shots" : "sweeps",
         res.cache.rows_computed, res.cache.rows_reused, res.unshot_fraction, res.timings.total);
    if (res.stiffness.action != "none")
        info("stiff scene: {} after {} shots ({} products with the rows): {}", res.stiffness.action,
             res.stiffness.switched_at_shot, res.stiffness.krylov_products, res.stiffness.reason);
    report_result(report, res, so, scene.size());
}

SolveResult solve_and_report(const Scene& scene, RowProvider& rows, SolverOptions so, Report& report) {
    so = front_end_solver_options(std::move(so));
    const SolveResult res = solve_radiosity(scene, rows, so);
    report_solve(scene, res, so, report);
    return res;
}

}  // namespace ffcube
