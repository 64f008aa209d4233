// Shared by radiate.cpp (gray) and radiate_bands.cpp (spectral bands): the checks of emissivities and temperatures, and the reflection operator with its GMRES solve.
#pragma once

#include <fmt/format.h>

#include <algorithm>
#include <charconv>
#include <chrono>
#include <cmath>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "ffcube/core/error.hpp"
#include "ffcube/solver/linear.hpp"
#include "ffcube/solver/radiate.hpp"

namespace ffcube::radiate_detail {


inline double seconds_since(std::chrono::steady_clock::time_point t0) {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

inline void check_emissivity(double e, const std::string& where) {
    if (!(e > 0.0 && e <= 1.0))
        throw InputError(fmt::format("{}: emissivity {} must be in (0, 1] (a perfect reflector, 0, neither emits nor "
                                     "absorbs: leave it out of the scene or give it a small emissivity)",
                                     where, e));
}
inline void check_temperature(double t, const std::string& where) {
    if (!(t >= 0.0 && std::isfinite(t))) throw InputError(fmt::format("{}: temperature {} K must be finite and >= 0", where, t));
}

inline double emissive_power(double t) {  // σ T⁴
    const double t2 = t * t;
    return kStefanBoltzmann * t2 * t2;
}

// y = x − c ∘ (F x), the operator of both problems (c = 1 − ε for a patch that reflects what it
// receives on top of a given emission, 1 for a patch whose net flux is given).
struct ReflectionOperator {
    const RowProduct& F;
    std::span<const double> c;
    void gather(std::span<const double> x, std::span<double> g) const { F.multiply(x, g); }  // g = F x
    void operator()(std::span<const double> x, std::span<double> y) const {
        gather(x, y);
        for (std::size_t i = 0; i < y.size(); ++i) y[i] = x[i] - c[i] * y[i];
    }
};

inline double norm2(std::span<const double> v) {
    double s = 0.0;
    for (const double x : v) s += x * x;
    return std::sqrt(s);
}

struct SolveOutcome {
    std::uint64_t iterations = 0;
    double residual = 0.0;  // relative
};

// Solves (I − diag(c) F) x = b from x's start value; NotConvergedError naming `what` unless the
// relative residual reaches options.tolerance.
inline SolveOutcome solve_reflections(const ReflectionOperator& op, std::span<const double> b, std::span<double> x,
                               const RadiateOptions& options, const std::string& what) {
    const double bnorm = norm2(b);
    if (bnorm == 0.0) {  // nothing emits and nothing is given: J = 0 exactly
        std::fill(x.begin(), x.end(), 0.0);
        return {};
    }
    GmresControl control;
    control.restart = options.restart;
    control.max_iterations = options.max_iterations;
    control.tolerance = options.tolerance * bnorm;
    control.inner_tolerance = 0.5 * control.tolerance;  // so that the true residual passes after the cycle
    const GmresOutcome out = gmres(op, b, x, control, [](std::span<const double> r) { return norm2(r); });
    const SolveOutcome result{out.iterations, out.measure / bnorm};
    if (!out.converged)
        throw NotConvergedError(fmt::format(
            "{}: GMRES({}) stopped {} after {} products with the rows at a relative residual of {:.3g} > tolerance {:.3g}; "
            "nothing was written",
            what, options.restart, out.stagnated ? "without progress" : "at the iteration limit", out.iterations,
            result.residual, options.tolerance));
    return result;
}

inline std::vector<double> sky_view_factors(const RowProduct& F) {
    std::vector<double> sky = F.row_sums();
    for (double& s : sky) s = 1.0 - s;
    return sky;
}

inline void check_sizes(const RowProduct& F, std::size_t area, std::size_t other, const char* what) {
    if (area != F.size() || other != F.size())
        throw InputError(fmt::format("radiation: F has {} rows, {} areas and {} {}: one each per patch", F.size(), area,
                                     other, what));
}

// The checks every solve starts with (options, sizes, areas, specs; an open scene without a sky
// temperature; no temperature at all): fills r.min_emissivity and r.sky_view, returns σT_sky⁴ (0
// without a sky). InputError naming the patch and the rule. radiate.cpp.
double prepare_radiation(const RowProduct& F, std::span<const double> area, std::span<const SurfaceSpec> spec,
                         const RadiateOptions& options, RadiateResult& r);
// r.power, r.sky, r.absolute_power and r.balance_error from r.heat_flux, r.radiosity, r.sky_view.
void finish_energy(RadiateResult& r, std::span<const double> area, double sky_power);

}  // namespace ffcube::radiate_detail
