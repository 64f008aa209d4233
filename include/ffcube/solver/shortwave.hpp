// Shortwave with reflections for a series of sun positions (docs/urban.md, "A day of shortwave").
// Every patch is a gray, diffuse reflector of albedo ρ_i < 1. What arrives at patch i from the sun
// and the sky, Q_i (W), is reflected as P_i = ρ_i (Q_i + R_i), and R = Fᵀ P is what arrives from
// the other patches' reflections: the energy leaving j reaches i as P_j F_ji (row j of F, the
// sender's own row, so that every watt a patch sends is accounted for whether or not F is
// reciprocal). Absorbed: (1 − ρ_i)(Q_i + R_i); escaped (to the sky): Σ_j P_j (1 − Σ_i F_ji).
// With the exact solution, Σ absorbed + escaped = Σ Q for every right-hand side.
// Pure CPU; deterministic whatever the thread count.
#pragma once

#include <cstdint>
#include <functional>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "ffcube/formfactor/sparse.hpp"

namespace ffcube {

// F and the albedos, prepared once for many solves: the transposed rows (what arrives at i from
// every j, gathered row by row) and each sender's escape share 1 − Σ_i F_ji (from the same float
// values, so that the balance closes to rounding).
struct ShortwaveSystem {
    std::uint32_t n = 0;
    std::vector<std::uint64_t> t_ptr;  // Fᵀ in CSR: row i holds the j with F_ji > 0
    std::vector<std::uint32_t> t_col;    // empty when t_col16 holds the columns
    std::vector<std::uint16_t> t_col16;  // the same columns in 16 bits when n ≤ 65,536 (6 bytes an entry streamed, not 8)
    std::vector<float> t_val;
    std::vector<double> albedo;  // per patch, in [0, 1)
    std::vector<double> escape;  // per patch: 1 − Σ_i F_ji (may be slightly negative for a row above 1)
    // max_j Σ_i ρ_i F_ji: the contraction factor of one sweep in the L1 norm (< 1 is required).
    double contraction = 0.0;
};

// InputError when an albedo is outside [0, 1) or the sweeps would not contract (a row of F whose
// sum exceeds 1/ρ); `patch_name(i)` names patch i in that message.
ShortwaveSystem make_shortwave_system(const CsrMatrix& F, std::vector<double> albedo,
                                      const std::function<std::string(std::uint32_t)>& patch_name);

struct ShortwaveControl {
    // Stop when Σ_i |R_i − R_i(previous)| ≤ tolerance × Σ_i Q_i for every right-hand side: the
    // balance Σ absorbed + escaped − Σ Q is bounded by that change (shortwave.cpp).
    double tolerance = 1e-12;
    std::uint32_t max_iterations = 100000;
    unsigned threads = 0;  // 0: hardware concurrency
};

// k right-hand sides at once, patch-major: incident[i * k + s] is Q_i of right-hand side s (W).
struct ShortwaveSolution {
    std::uint32_t k = 0;
    std::vector<double> reflected;  // R, patch-major like incident (W arriving from reflections)
    std::vector<double> absorbed;   // (1 − ρ_i)(Q_i + R_i), patch-major (W)
    std::vector<double> escaped;    // per right-hand side (W)
    std::uint32_t iterations = 0;   // sweeps and the last product (passes over Fᵀ)
    double change = 0.0;            // the last product's largest Σ|ΔR| / Σ Q: bounds the balance error
};

// Gauss–Seidel sweeps on all right-hand sides together (one pass over Fᵀ serves k of them), then
// one product with Fᵀ that closes the balance (shortwave.cpp). NotConvergedError after
// max_iterations.
ShortwaveSolution solve_shortwave(const ShortwaveSystem& system, std::span<const double> incident, std::uint32_t k,
                                  const ShortwaveControl& control = {});

// A sun-series file (docs/urban.md): the header
//   time,azimuth,elevation,direct_normal_irradiance,diffuse_horizontal_irradiance
// or time,sun_x,sun_y,sun_z,direct_normal_irradiance,diffuse_horizontal_irradiance, then one line per
// step; blank lines and lines starting with '#' are skipped. Irradiances in W/m² (finite, ≥ 0).
struct SunStep {
    std::string time;       // as written (non-empty, unique)
    double x = 0, y = 0, z = 0;  // unit direction towards the sun
    double elevation = 0;   // degrees above the horizon (asin z)
    double dni = 0, dhi = 0;
    std::size_t line = 0;
};
// InputError naming source:line and the rule broken.
std::vector<SunStep> parse_sun_series(std::string_view text, const std::string& source);

// An albedo file: the header object,albedo, then one line per object, each albedo in [0, 1). Every
// object of `objects` must be listed once; an unknown, repeated or missing object is an InputError.
// Returns the albedo per object, in the order of `objects`.
std::vector<double> parse_albedo_csv(std::string_view text, const std::string& source, const std::vector<std::string>& objects);

}  // namespace ffcube
