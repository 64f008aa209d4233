// Non-gray radiative exchange by spectral bands (solver/radiate.hpp, docs/radiate.md "Spectral
// bands"): blackbody fractions by series, the bands CSV, and the band solves with the outer
// iteration for the temperatures of heat-flux patches.
#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>

#include "ffcube/core/csv_input.hpp"
#include "ffcube/core/error.hpp"
#include "ffcube/solver/radiate.hpp"
#include "radiate_internal.hpp"

namespace ffcube {
using namespace radiate_detail;
namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr double kPlanckNorm = 15.0 / (kPi * kPi * kPi * kPi);  // 15/π⁴: ∫₀^∞ u³/(e^u − 1) du = π⁴/15
constexpr double kInf = std::numeric_limits<double>::infinity();

// B_2m / (2m)! for m = 1..15 (Bernoulli numbers: B2 = 1/6, B4 = −1/30, ..., B30 = 8615841276005/14322).
// |B_2m|/(2m)! ≈ 2/(2π)^{2m}, so at ζ < 2 the m-th term is below 2·8·(1/π)^{2m}/(2m + 3): 15 terms
// reach 6e-16 of the leading ζ³/3.
double bernoulli_over_factorial(int m) {
    static const double b[15][2] = {{1.0, 6.0},
                                    {-1.0, 30.0},
                                    {1.0, 42.0},
                                    {-1.0, 30.0},
                                    {5.0, 66.0},
                                    {-691.0, 2730.0},
                                    {7.0, 6.0},
                                    {-3617.0, 510.0},
                                    {43867.0, 798.0},
                                    {-174611.0, 330.0},
                                    {854513.0, 138.0},
                                    {-236364091.0, 2730.0},
                                    {8553103.0, 6.0},
                                    {-23749461029.0, 870.0},
                                    {8615841276005.0, 14322.0}};
    double factorial = 1.0;
    for (int k = 2; k <= 2 * m; ++k) factorial *= k;
    return b[m - 1][0] / b[m - 1][1] / factorial;
}

// F at the lower edge `edge` (µm) of a band for temperature t: 0 at edge 0, 1 at +inf (also at t = 0,
// where the emission is 0 anyway).
double fraction_at(double edge, double t) {
    if (edge == 0.0) return 0.0;
    if (std::isinf(edge)) return 1.0;
    return blackbody_fraction(edge * t);
}
double slope_at(double edge, double t) {
    if (edge == 0.0 || std::isinf(edge)) return 0.0;
    return blackbody_fraction_slope(edge * t);
}

std::string band_name(const BandModel& m, std::uint32_t k) {
    return fmt::format("band {} ({:g} to {:g} um)", k, m.edges[k], m.edges[k + 1]);
}

}  // namespace

double blackbody_fraction(double x) {
    if (std::isnan(x) || x < 0.0) throw InputError(fmt::format("blackbody fraction at lambda*T = {}: must be >= 0", x));
    if (x == 0.0) return 0.0;
    if (std::isinf(x)) return 1.0;
    const double z = kSecondRadiationConstant / x;
    if (z >= 2.0) {  // exponential series: terms fall as e^{−nζ} ≤ e^{−2n}
        double sum = 0.0;
        for (int n = 1; n <= 64; ++n) {
            const double dn = n;
            const double term = std::exp(-dn * z) / dn * (z * z * z + 3.0 * z * z / dn + 6.0 * z / (dn * dn) + 6.0 / (dn * dn * dn));
            sum += term;
            if (term < 1e-18 * sum) break;
        }
        return kPlanckNorm * sum;
    }
    // ∫₀^ζ u³/(e^u − 1) du = Σ_n B_n ζ^{n+3}/(n!(n + 3)) = ζ³/3 − ζ⁴/8 + Σ_m B_2m ζ^{2m+3}/((2m)!(2m + 3)).
    const double z2 = z * z;
    double sum = z * z2 / 3.0 - z2 * z2 / 8.0;
    double power = z2 * z;  // ζ^{2m+3}, from m = 0
    for (int m = 1; m <= 15; ++m) {
        power *= z2;
        sum += bernoulli_over_factorial(m) * power / (2.0 * m + 3.0);
    }
    return 1.0 - kPlanckNorm * sum;
}

double blackbody_fraction_slope(double x) {
    if (!(x > 0.0) || std::isinf(x)) return 0.0;
    const double z = kSecondRadiationConstant / x;
    if (z > 700.0) return 0.0;  // e^ζ overflows; the slope is below 1e-290
    return kPlanckNorm * z * z * z * z / std::expm1(z);
}

std::vector<NamedBand> parse_bands_csv(std::string_view text, const std::string& source) {
    static const CsvHeader kHeader = {"object", "lambda_min_um", "lambda_max_um", "emissivity"};
    std::vector<NamedBand> out;
    for (const CsvRow& row : parse_csv(text, source, std::span(&kHeader, 1)).rows) {
        const std::vector<std::string>& f = row.fields;
        if (f[0].empty()) row.fail("the object name is empty");
        NamedBand b;
        b.object = f[0];
        b.line = row.line;
        const std::optional<double> lo = row.number(1);
        std::optional<double> hi;
        if (f[2] == "inf" || f[2] == "Inf" || f[2] == "infinity")
            hi = kInf;
        else
            hi = row.number(2);
        const std::optional<double> eps = row.number(3);
        if (!lo || !hi || !eps) row.fail(fmt::format("'{}': every field is required (lambda_max_um may be 'inf')", b.object));
        check_emissivity(*eps, row.where);
        if (*lo < 0.0) row.fail(fmt::format("lambda_min_um {} must be >= 0", *lo));
        if (!(*lo < *hi))
            row.fail(fmt::format("band [{}, {}] um of '{}' is inverted or empty: lambda_min_um must be below lambda_max_um",
                                 *lo, *hi, b.object));
        b.lambda_min = *lo;
        b.lambda_max = *hi;
        b.emissivity = *eps;
        out.push_back(std::move(b));
    }
    // Overlaps, object by object (touching bands, max = next min, are fine).
    std::map<std::string, std::vector<const NamedBand*>> by_object;
    for (const NamedBand& b : out) by_object[b.object].push_back(&b);
    for (auto& [object, bands] : by_object) {
        std::sort(bands.begin(), bands.end(), [](const NamedBand* a, const NamedBand* b) {
            return a->lambda_min != b->lambda_min ? a->lambda_min < b->lambda_min : a->line < b->line;
        });
        for (std::size_t k = 1; k < bands.size(); ++k) {
            const NamedBand& a = *bands[k - 1];
            const NamedBand& b = *bands[k];
            if (b.lambda_min < a.lambda_max) {
                const NamedBand& later = a.line > b.line ? a : b;
                const NamedBand& earlier = a.line > b.line ? b : a;
                throw InputError(fmt::format("{}:{}: band [{}, {}] um of '{}' overlaps its band [{}, {}] um on line {}",
                                             source, later.line, later.lambda_min, later.lambda_max, object,
                                             earlier.lambda_min, earlier.lambda_max, earlier.line));
            }
        }
    }
    return out;
}

BandModel bands_for_objects(std::span<const std::string> objects, std::span<const NamedBand> lines,
                            const std::string& source, std::span<const double> gray) {
    if (gray.size() != objects.size())
        throw InputError(fmt::format("bands: {} gray emissivities for {} objects", gray.size(), objects.size()));
    const ObjectIndex index(objects);
    std::vector<std::vector<const NamedBand*>> of(objects.size());
    BandModel m;
    m.edges = {0.0, kInf};
    for (const NamedBand& b : lines) {
        of[index.at(b.object, fmt::format("{}:{}", source, b.line))].push_back(&b);
        m.edges.push_back(b.lambda_min);
        m.edges.push_back(b.lambda_max);
    }
    std::sort(m.edges.begin(), m.edges.end());
    m.edges.erase(std::unique(m.edges.begin(), m.edges.end()), m.edges.end());
    const std::uint32_t K = m.bands();
    m.emissivity.assign(objects.size() * K, 0.0);
    for (std::size_t o = 0; o < objects.size(); ++o)
        for (std::uint32_t k = 0; k < K; ++k) {
            double e = gray[o];  // a gap (or outside every band of o): the gray emissivity
            for (const NamedBand* b : of[o])
                if (b->lambda_min <= m.edges[k] && m.edges[k + 1] <= b->lambda_max) e = b->emissivity;
            m.emissivity[o * K + k] = e;
        }
    return m;
}

RadiateResult solve_radiation_bands(const CsrMatrix& F, std::span<const double> area, std::span<const SurfaceSpec> spec,
                                    std::span<const std::uint32_t> group, const BandModel& bands,
                                    const RadiateOptions& options) {
    return solve_radiation_bands(CsrRowProduct(F, options.threads), area, spec, group, bands, options);
}

RadiateResult solve_radiation_bands(const RowProduct& F, std::span<const double> area, std::span<const SurfaceSpec> spec,
                                    std::span<const std::uint32_t> group, const BandModel& bands,
                                    const RadiateOptions& options) {
    const auto t0 = std::chrono::steady_clock::now();
    RadiateResult r;
    const double sky_power = prepare_radiation(F, area, spec, options, r);
    const std::uint32_t n = F.size();
    const std::uint32_t K = bands.bands();
    if (K < 1 || bands.edges.front() != 0.0 || !std::isinf(bands.edges.back()) || bands.emissivity.size() % K != 0)
        throw InputError("bands: the partition must run from 0 to +inf um, with K emissivities per object");
    if (!(options.outer_tolerance > 0.0) || options.max_outer_iterations < 1)
        throw InputError("bands: the outer tolerance must be > 0 and the outer iterations >= 1");
    const std::size_t groups = bands.emissivity.size() / K;
    if (group.size() != n) throw InputError(fmt::format("bands: {} group indices for {} patches", group.size(), n));
    r.min_emissivity = 1.0;
    for (std::uint32_t i = 0; i < n; ++i) {
        if (group[i] >= groups) throw InputError(fmt::format("bands: patch {}: object {} out of range", i, group[i]));
        for (std::uint32_t k = 0; k < K; ++k) {
            check_emissivity(bands.emissivity[group[i] * K + k], fmt::format("patch {} {}", i, band_name(bands, k)));
            r.min_emissivity = std::min(r.min_emissivity, bands.emissivity[group[i] * K + k]);
        }
    }
    r.bands = K;
    const double t_sky = options.sky_temperature.value_or(0.0);

    // Temperatures: given, or (heat-flux patches) from the largest given one (sky included), then corrected.
    std::vector<double> temp(n), e(n);  // T and σT⁴
    double t_start = t_sky;
    bool any_flux = false;
    for (std::uint32_t i = 0; i < n; ++i)
        if (spec[i].condition == SurfaceCondition::Temperature) t_start = std::max(t_start, spec[i].value);
    for (std::uint32_t i = 0; i < n; ++i) {
        const bool given = spec[i].condition == SurfaceCondition::Temperature;
        any_flux = any_flux || !given;
        temp[i] = given ? spec[i].value : t_start;
        e[i] = emissive_power(temp[i]);
    }

    std::vector<std::vector<double>> jk(K);  // each band's radiosity, kept as the next start
    std::vector<double> c(n), b(n), g(n), q(n);
    r.radiosity.assign(n, 0.0);
    r.irradiation.assign(n, 0.0);
    // All bands at the current temperatures: fills r.radiosity, r.irradiation and q (the net flux
    // each patch has at its temperature; for a heat-flux patch, what the outer iteration compares).
    const auto sweep = [&] {
        std::fill(r.radiosity.begin(), r.radiosity.end(), 0.0);
        std::fill(r.irradiation.begin(), r.irradiation.end(), 0.0);
        std::fill(q.begin(), q.end(), 0.0);
        for (std::uint32_t k = 0; k < K; ++k) {
            const double sky_band = (fraction_at(bands.edges[k + 1], t_sky) - fraction_at(bands.edges[k], t_sky)) * sky_power;
            const bool first = jk[k].empty();
            if (first) jk[k].resize(n);
            for (std::uint32_t i = 0; i < n; ++i) {
                const double eps = bands.emissivity[group[i] * K + k];
                const double emission = (fraction_at(bands.edges[k + 1], temp[i]) - fraction_at(bands.edges[k], temp[i])) * e[i];
                c[i] = 1.0 - eps;
                b[i] = eps * emission + c[i] * (r.sky_view[i] * sky_band);
                if (first) jk[k][i] = emission;
            }
            const ReflectionOperator op{F, c};
            const SolveOutcome solved = solve_reflections(op, b, jk[k], options, band_name(bands, k));
            r.iterations += solved.iterations;
            r.residual = std::max(r.residual, solved.residual);
            op.gather(jk[k], g);
            for (std::uint32_t i = 0; i < n; ++i) {
                const double eps = bands.emissivity[group[i] * K + k];
                const double emission = (fraction_at(bands.edges[k + 1], temp[i]) - fraction_at(bands.edges[k], temp[i])) * e[i];
                g[i] += r.sky_view[i] * sky_band;
                q[i] += eps * (emission - g[i]);
                r.radiosity[i] += jk[k][i];
                r.irradiation[i] += g[i];
            }
        }
    };

    std::vector<double> dj(n), residual(n), eps_bar(n), gathered(n);
    for (std::uint32_t outer = 0;; ++outer) {
        sweep();
        if (!any_flux) break;
        double scale = sky_power, worst = 0.0;
        std::uint32_t at_zero = 0;
        for (std::uint32_t i = 0; i < n; ++i) {
            scale = std::max(scale, e[i]);
            if (spec[i].condition == SurfaceCondition::HeatFlux) scale = std::max(scale, std::abs(spec[i].value));
        }
        for (std::uint32_t i = 0; i < n; ++i) {
            residual[i] = spec[i].condition == SurfaceCondition::HeatFlux ? spec[i].value - q[i] : 0.0;
            worst = std::max(worst, std::abs(residual[i]));
            if (spec[i].condition == SurfaceCondition::HeatFlux && e[i] == 0.0) ++at_zero;
        }
        r.outer_iterations = outer + 1;
        r.outer_residual = scale > 0.0 ? worst / scale : 0.0;
        if (r.outer_residual <= options.outer_tolerance) break;
        if (outer + 1 >= options.max_outer_iterations)
            throw NotConvergedError(fmt::format(
                "bands: the temperatures of the heat-flux surfaces did not converge in {} outer iterations (flux "
                "residual {:.3g} of the largest emissive power > {:.3g}){}; nothing was written",
                outer + 1, r.outer_residual, options.outer_tolerance,
                at_zero ? fmt::format("; {} patches are held at 0 K: their heat flux may need a temperature below 0 K",
                                      at_zero)
                        : std::string()));
        // The gray linearised response: a heat-flux patch's σT⁴ changes by Δe, which it emits in band k
        // as f_ik Δe (f_ik = ∂E_bk/∂(σT⁴) at T_i, Σ_k f_ik = 1) with emissivity ε_ik: in one gray
        // system, ε̄_i = Σ_k ε_ik f_ik. What the other patches reflect of it is in the spectrum of that
        // change, w_k ∝ Σ_{heat-flux i} A_i ε_ik f_ik: they reflect 1 − Σ_k ε_jk w_k. Then
        // Δq = ε̄(Δe − ΔG) on heat-flux patches (Δe = 0 on the others): ΔJ − c ∘ F ΔJ = (0 | r).
        std::vector<double> w(K, 0.0), f(K);
        double w_sum = 0.0;
        for (std::uint32_t i = 0; i < n; ++i) {
            double eps_bar_i = 0.0, lo = 1.0, hi = 0.0;
            for (std::uint32_t k = 0; k < K; ++k) {
                const double eps = bands.emissivity[group[i] * K + k];
                const double df = fraction_at(bands.edges[k + 1], temp[i]) - fraction_at(bands.edges[k], temp[i]);
                const double ds = slope_at(bands.edges[k + 1], temp[i]) - slope_at(bands.edges[k], temp[i]);
                f[k] = df + 0.25 * ds;
                eps_bar_i += eps * f[k];
                lo = std::min(lo, eps);
                hi = std::max(hi, eps);
            }
            eps_bar[i] = std::clamp(eps_bar_i, lo, hi);
            if (spec[i].condition == SurfaceCondition::HeatFlux)
                for (std::uint32_t k = 0; k < K; ++k) {
                    const double x = area[i] * bands.emissivity[group[i] * K + k] * f[k];
                    w[k] += x;
                    w_sum += x;
                }
        }
        for (std::uint32_t i = 0; i < n; ++i) {
            const bool flux = spec[i].condition == SurfaceCondition::HeatFlux;
            double reflect = 1.0 - eps_bar[i];
            if (!flux && w_sum > 0.0) {
                double eps_w = 0.0, lo = 1.0, hi = 0.0;
                for (std::uint32_t k = 0; k < K; ++k) {
                    const double eps = bands.emissivity[group[i] * K + k];
                    eps_w += eps * w[k] / w_sum;
                    lo = std::min(lo, eps);
                    hi = std::max(hi, eps);
                }
                reflect = 1.0 - std::clamp(eps_w, lo, hi);
            }
            c[i] = flux ? 1.0 : reflect;
            b[i] = residual[i];
            dj[i] = b[i];
        }
        const ReflectionOperator op{F, c};
        const SolveOutcome solved = solve_reflections(op, b, dj, options, "bands: the temperature correction");
        r.iterations += solved.iterations;
        op.gather(dj, gathered);
        for (std::uint32_t i = 0; i < n; ++i) {
            if (spec[i].condition != SurfaceCondition::HeatFlux) continue;
            e[i] = std::max(0.0, e[i] + gathered[i] + residual[i] / eps_bar[i]);
            temp[i] = std::pow(e[i] / kStefanBoltzmann, 0.25);
        }
    }
    r.heat_flux.resize(n);
    r.temperature = temp;
    for (std::uint32_t i = 0; i < n; ++i)
        r.heat_flux[i] = spec[i].condition == SurfaceCondition::HeatFlux ? spec[i].value : q[i];
    finish_energy(r, area, sky_power);
    r.seconds = seconds_since(t0);
    return r;
}

}  // namespace ffcube
