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

// The rows of F as the solves use them: products y = F x and row sums, never a dense matrix. Held
// in memory (CsrRowProduct) or read block by block from a .ffm file at every product (the command
// line's streamed rows, src/cli): either way y_i is row i's sum in column order, so the results are
// the same bits.
class RowProduct {
public:
    virtual ~RowProduct() = default;
    virtual std::uint32_t size() const = 0;
    virtual void multiply(std::span<const double> x, std::span<double> y) const = 0;  // y = F x
    virtual std::vector<double> row_sums() const = 0;                                // RowView::sum of each row
};

// F in memory. The product is split over `threads` (0: every core) in row ranges of equal nonzeros
// from a million nonzeros on (a thread start costs ~50 us); the same bits for any number.
class CsrRowProduct final : public RowProduct {
public:
    CsrRowProduct(const CsrMatrix& F, unsigned threads) : F_(F), threads_(threads) {}
    std::uint32_t size() const override { return F_.size(); }
    void multiply(std::span<const double> x, std::span<double> y) const override;
    std::vector<double> row_sums() const override;

private:
    const CsrMatrix& F_;
    unsigned threads_;
};

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
    // Spectral bands (solve_radiation_bands): the outer iteration that finds the temperatures of
    // heat-flux patches stops when max_i |q_i − q_given,i| ≤ outer_tolerance × the largest σT⁴ of
    // the problem (patches, sky, |q_given|), and is refused (NotConvergedError) after
    // max_outer_iterations.
    double outer_tolerance = 1e-8;
    // Threads for the products with the rows (0: every core; used from a million nonzeros). The
    // results are the same bits for any number.
    unsigned threads = 0;
    std::uint32_t max_outer_iterations = 50;
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
    std::uint32_t bands = 1;           // spectral bands solved (1: gray)
    std::uint32_t outer_iterations = 0;  // band solves of every band, for heat-flux patches (0: none needed)
    double outer_residual = 0.0;       // max |q_i − q_given,i| / the largest σT⁴, at the end
    double seconds = 0.0;
};

// Solves the enclosure. area[i] > 0, spec[i] per patch (F's size). Throws InputError for an open
// scene without a sky temperature (saying the area-weighted mean and the max of F_sky), for a
// problem without any temperature (no temperature given and no sky: temperatures undetermined),
// and for a heat flux no surface temperature ≥ 0 K can give (q_i < −ε_i G_i); NotConvergedError
// (exit 5) when GMRES stops short of the tolerance. The result is always converged.
RadiateResult solve_radiation(const CsrMatrix& F, std::span<const double> area, std::span<const SurfaceSpec> spec,
                              const RadiateOptions& options);
// The same on rows given as products (CsrRowProduct, or streamed from a file).
RadiateResult solve_radiation(const RowProduct& F, std::span<const double> area, std::span<const SurfaceSpec> spec,
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
ConductanceResult radiative_conductances(const RowProduct& F, std::span<const double> area,
                                         std::span<const double> emissivity, std::span<const std::uint32_t> object,
                                         std::uint32_t objects, const RadiateOptions& options);

// ---- Spectral bands (docs/radiate.md, "Spectral bands") ----

// c₂ = hc/k_B, µm·K (CODATA 2018, exact: 1.438776877... × 10⁻² m·K).
inline constexpr double kSecondRadiationConstant = 14387.76877;

// F(0 → λT): the share of a blackbody's emissive power σT⁴ below wavelength λ at temperature T,
// for x = λT in µm·K (0 → 0, +inf → 1). By series, not a table: for ζ = c₂/x ≥ 2 the exponential
// series (15/π⁴) Σ_n e^{−nζ}/n (ζ³ + 3ζ²/n + 6ζ/n² + 6/n³); below, 1 − (15/π⁴) ∫₀^ζ u³/(e^u − 1) du
// by its Bernoulli series (Chang & Rhee, Int. Comm. Heat Mass Transfer 11 (1984) 451; Siegel &
// Howell, Thermal Radiation Heat Transfer, §2.6). Both to ~1e-16.
double blackbody_fraction(double lambda_t);
// x dF/dx at x = λT: (15/π⁴) ζ⁴/(e^ζ − 1), ζ = c₂/x (0 at x = 0 and +inf).
double blackbody_fraction_slope(double lambda_t);

// One line of a bands CSV (`object,lambda_min_um,lambda_max_um,emissivity`).
struct NamedBand {
    std::string object;
    double lambda_min = 0.0, lambda_max = 0.0;  // µm, 0 ≤ min < max ≤ +inf ("inf")
    double emissivity = 1.0;                    // (0, 1]
    std::size_t line = 0;
};

// Parses a bands CSV: the header, then one line per band; lambda_max may be `inf`. Refused with
// "SOURCE:LINE: rule" (InputError): a bad header or field count, a missing or non-numeric value, an
// emissivity outside (0, 1], lambda_min < 0, an inverted or empty band (min ≥ max), and two bands
// of one object that overlap (naming both lines).
std::vector<NamedBand> parse_bands_csv(std::string_view text, const std::string& source);

// Every object's emissivity in every band of a common partition of (0, +inf) µm.
struct BandModel {
    std::vector<double> edges;       // µm: 0 = edges[0] < ... < edges[K] = +inf
    std::vector<double> emissivity;  // [object × K + k]
    std::uint32_t bands() const { return static_cast<std::uint32_t>(edges.size() - 1); }
};

// The partition of (0, +inf) by every band edge of every object, and each object's emissivity in
// each piece: its band's where one covers it, its gray emissivity (`gray[k]`, from the surfaces
// CSV) in the gaps between and outside its bands. A line naming an object the scene does not have
// is refused with SOURCE:LINE.
BandModel bands_for_objects(std::span<const std::string> objects, std::span<const NamedBand> lines,
                            const std::string& source, std::span<const double> gray);

// Non-gray exchange: band k of every patch emits ε_ik (F(0→λ_{k+1}T_i) − F(0→λ_k T_i)) σT_i⁴ and
// reflects 1 − ε_ik (patch i takes the emissivities of object group[i]); the sky is a blackbody at
// T_sky. Each band is one solve of the gray system (solve_radiation's); the bands are summed. A
// patch with a given heat flux gets its temperature by an outer iteration: all bands at the
// current temperatures, then a gray correction solve (the linearised response with the emissivity
// ε̄_i = Σ_k ε_ik ∂E_bk/∂(σT⁴) at T_i) for the σT⁴ that cancels the flux residual — Newton's method
// with a gray Jacobian, exact in one step when the emissivities are flat over the bands. Refused
// with NotConvergedError when it has not converged in options.max_outer_iterations. spec[i]'s
// emissivity is not used (the bands give it). With one band [0, +inf) and temperatures only, the
// result is solve_radiation's bit for bit.
RadiateResult solve_radiation_bands(const CsrMatrix& F, std::span<const double> area, std::span<const SurfaceSpec> spec,
                                    std::span<const std::uint32_t> group, const BandModel& bands,
                                    const RadiateOptions& options);
RadiateResult solve_radiation_bands(const RowProduct& F, std::span<const double> area, std::span<const SurfaceSpec> spec,
                                    std::span<const std::uint32_t> group, const BandModel& bands,
                                    const RadiateOptions& options);

}  // namespace ffcube
