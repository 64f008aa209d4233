// Gray-body radiative exchange in an enclosure of diffuse gray patches, by the net radiation
// method (Oppenheim's radiosity formulation; Modest, Radiative Heat Transfer, ch. 6), on the rows
// of F: never a dense N × N matrix. docs/radiate.md has the equations and their derivation.
//
//   J_i: radiosity (W/m², power leaving per unit area), the unknown;
//   G_i = Σ_j F_ij J_j + F_sky,i σ T_sky⁴: irradiation (power arriving per unit area),
//         F_sky,i = 1 − Σ_j F_ij the share of i's hemisphere that escapes the scene;
//   q_i = J_i − G_i: net heat flux leaving i (W/m²);
//   J_i = ε_i σ T_i⁴ + (1 − ε_i) G_i (gray, diffuse, opaque).
//
// A patch has either a temperature (then J_i − (1 − ε_i) Σ_j F_ij J_j = ε_i σ T_i⁴ + (1 − ε_i)
// F_sky,i σ T_sky⁴) or a net heat flux (then J_i − Σ_j F_ij J_j = q_i + F_sky,i σ T_sky⁴; an
// adiabatic, reradiating wall has q = 0). Mixed conditions make the system non-symmetric; it is
// solved by restarted GMRES (solver/linear.hpp) on the rows.
//
// Conductances (radiative exchange factors): GR_kl = ε_k A_k B_kl between objects k and l, B
// Gebhart's absorption factors (reflections included), one GMRES solve per emitting object.
#pragma once

#include <cstdint>
#include <functional>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "ffcube/formfactor/sparse.hpp"

namespace ffcube {

// CODATA 2018 (exact since the 2019 SI): W m⁻² K⁻⁴.
inline constexpr double kStefanBoltzmann = 5.670374419e-8;

enum class SurfaceCondition : std::uint8_t { Temperature, HeatFlux };

// What one surface (object or patch) is given: its emissivity in (0, 1] and either its
// temperature (K, ≥ 0) or the net heat flux leaving it (W/m², adiabatic = 0).
struct SurfaceSpec {
    double emissivity = 1.0;
    SurfaceCondition condition = SurfaceCondition::Temperature;
    double value = 0.0;  // K or W/m², as condition says
};

// One line of a surfaces CSV (`object,emissivity,temperature,heat_flux`), with its line number.
struct NamedSurface {
    std::string object;
    SurfaceSpec spec;
    std::size_t line = 0;
};

// Parses a surfaces CSV: a header `object,emissivity,temperature,heat_flux` (first line that is
// not blank or a '#' comment), then one line per object, exactly one of temperature and heat_flux
// given (the other empty). Object names may be double-quoted (then "" is a quote). Every bad
// value, a missing header, a wrong field count and a repeated object are refused with an
// InputError "SOURCE:LINE: ..." naming the rule.
std::vector<NamedSurface> parse_surfaces_csv(std::string_view text, const std::string& source);
// `--default-surface EPS,T`: emissivity and temperature. InputError naming the option otherwise.
SurfaceSpec parse_default_surface(std::string_view text);
// One spec per object, in `objects` order, from the parsed lines: an object the CSV does not list
// takes `fallback`, or is refused (InputError naming the object and the CSV) when there is none; a
// line naming an object the scene does not have is refused with its line.
std::vector<SurfaceSpec> surfaces_for_objects(std::span<const std::string> objects,
                                              std::span<const NamedSurface> lines, const std::string& source,
                                              const std::optional<SurfaceSpec>& fallback);

struct RadiateOptions {
    // K; what the escaping part of every hemisphere sees. Without it an open scene is refused.
    std::optional<double> sky_temperature;
    // Converged when ‖b − A J‖₂ ≤ tolerance × ‖b‖₂ (the true residual, recomputed by GMRES).
    double tolerance = 1e-10;
    std::uint64_t max_iterations = 5000;  // products with the rows, per solve
    std::uint32_t restart = 60;           // GMRES(m): Krylov vectors of N doubles held
    // A scene is open when some patch has F_sky,i above this.
    double open_threshold = 1e-6;
    // Names patch i in messages ("patch 12 of object 'floor'"); empty: "patch i".
    std::function<std::string(std::uint32_t)> patch_name;
};

// InputError naming the rule when an option, a spec or an area is out of range, or when the
// sizes differ.
void validate(const RadiateOptions& options);

struct RadiateResult {
    std::vector<double> radiosity;    // J, W/m²
    std::vector<double> irradiation;  // G, W/m²
    std::vector<double> heat_flux;    // q = J − G, W/m² (given ones echoed)
    std::vector<double> temperature;  // K (given ones echoed)
    std::vector<double> sky_view;     // F_sky = 1 − row sum (negative where a row sums above 1)
    std::uint64_t iterations = 0;     // products with the rows
    double residual = 0.0;            // ‖b − A J‖₂ / ‖b‖₂ at the end
    // Energy, W: power = Σ A_i q_i (net power leaving all patches); sky = Σ A_i F_sky,i (J_i −
    // σ T_sky⁴), the net power leaving to the sky; balance_error = |power − sky| / (Σ A_i |q_i| +
    // |sky|) (0 when both vanish): zero for reciprocal rows (A_i F_ij = A_j F_ji), else of the order
    // of the rows' reciprocity error.
    double power = 0.0, sky = 0.0, absolute_power = 0.0, balance_error = 0.0;
    double min_emissivity = 1.0;  // the stiffness: GMRES's work grows as it falls
    double seconds = 0.0;
};

// Solves the enclosure. area[i] > 0, spec[i] per patch (F's size). Throws InputError for an open
// scene without a sky temperature (saying the area-weighted mean and the max of F_sky), for a
// problem without any temperature (no temperature given and no sky: temperatures undetermined),
// and for a heat flux no surface temperature ≥ 0 K can give (q_i < −ε_i G_i); NotConvergedError
// (exit 5) when GMRES stops short of the tolerance. The result is always converged.
RadiateResult solve_radiation(const CsrMatrix& F, std::span<const double> area, std::span<const SurfaceSpec> spec,
                              const RadiateOptions& options);

struct ConductanceResult {
    // gr[k][l] = ε_k A_k B_kl (m²): the power object l absorbs, reflections included, of what object
    // k emits at unit blackbody exitance (σT⁴ = 1). gr[k][k] is what k absorbs of its own emission.
    std::vector<std::vector<double>> gr;
    std::vector<double> gr_sky;     // ε_k A_k B_k,sky: what escapes to the sky
    std::vector<double> emittance;  // ε_k A_k = Σ_{i∈k} ε_i A_i, m²
    std::uint64_t iterations = 0;   // products with the rows, all solves
    std::uint32_t solves = 0;       // one per object with ε_k A_k > 0
    double max_residual = 0.0;      // largest relative residual of the solves
    // max over k of |Σ_l B_kl + B_k,sky − 1|: zero for reciprocal rows.
    double sum_rule_error = 0.0;
    // max over k ≠ l of |GR_kl − GR_lk| / max(GR_kl, GR_lk), over pairs above 1e-9 of the largest.
    double reciprocity_error = 0.0;
    double seconds = 0.0;
};

// Gebhart conductances between `objects` groups of patches (object[i] < objects): for each
// object k, one solve of J − diag(1 − ε) F J = E with E_i = ε_i on k's patches and 0 elsewhere (unit
// blackbody exitance), then the power absorbed by patch j is ε_j A_j Σ_m F_jm J_m. Every patch
// reflects here (1 − ε_i), whatever its condition in the temperature problem: conductances are a
// property of geometry and emissivities. NotConvergedError when a solve does not converge.
ConductanceResult radiative_conductances(const CsrMatrix& F, std::span<const double> area,
                                         std::span<const double> emissivity, std::span<const std::uint32_t> object,
                                         std::uint32_t objects, const RadiateOptions& options);

}  // namespace ffcube
