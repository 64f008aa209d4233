// Gray-body radiative exchange by the net radiation method on the rows of F (solver/radiate.hpp,
// docs/radiate.md).
#include "ffcube/solver/radiate.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <charconv>
#include <chrono>
#include <cmath>
#include <map>
#include <thread>

#include "ffcube/core/csv_input.hpp"
#include "ffcube/core/error.hpp"
#include "ffcube/solver/linear.hpp"
#include "radiate_internal.hpp"

namespace ffcube {
using namespace radiate_detail;

std::vector<NamedSurface> parse_surfaces_csv(std::string_view text, const std::string& source) {
    static const CsvHeader kHeader = {"object", "emissivity", "temperature", "heat_flux"};
    std::vector<NamedSurface> out;
    std::map<std::string, std::size_t> seen;  // object → line
    for (const CsvRow& row : parse_csv(text, source, std::span(&kHeader, 1)).rows) {
        const std::string& object = row.fields[0];
        if (object.empty()) row.fail("the object name is empty");
        if (const auto it = seen.find(object); it != seen.end())
            row.fail(fmt::format("object '{}' is listed again (first on line {})", object, it->second));
        const std::optional<double> eps = row.number(1);
        if (!eps) row.fail(fmt::format("the emissivity of '{}' is missing", object));
        check_emissivity(*eps, row.where);
        const std::optional<double> t = row.number(2);
        const std::optional<double> q = row.number(3);
        if (t.has_value() == q.has_value())
            row.fail(fmt::format("'{}' gives {}; give exactly one of temperature (K) and heat_flux (W/m^2, adiabatic = 0) "
                                 "and leave the other empty",
                                 object, t ? "both a temperature and a heat flux" : "neither a temperature nor a heat flux"));
        if (t) check_temperature(*t, row.where);
        NamedSurface s;
        s.object = object;
        s.spec.emissivity = *eps;
        s.spec.condition = t ? SurfaceCondition::Temperature : SurfaceCondition::HeatFlux;
        s.spec.value = t ? *t : *q;
        s.line = row.line;
        seen.emplace(s.object, row.line);
        out.push_back(std::move(s));
    }
    return out;
}

SurfaceSpec parse_default_surface(std::string_view text) {
    const std::string where = fmt::format("--default-surface {}", text);
    const std::vector<std::string> f = split_csv(text, where);
    if (f.size() != 2) throw InputError(fmt::format("{}: expected EMISSIVITY,TEMPERATURE (two numbers)", where));
    const std::optional<double> eps = parse_csv_number(f[0], "emissivity", where);
    const std::optional<double> t = parse_csv_number(f[1], "temperature", where);
    if (!eps || !t) throw InputError(fmt::format("{}: expected EMISSIVITY,TEMPERATURE (two numbers)", where));
    check_emissivity(*eps, where);
    check_temperature(*t, where);
    return {*eps, SurfaceCondition::Temperature, *t};
}

std::vector<SurfaceSpec> surfaces_for_objects(std::span<const std::string> objects,
                                              std::span<const NamedSurface> lines, const std::string& source,
                                              const std::optional<SurfaceSpec>& fallback) {
    const ObjectIndex index(objects);
    std::vector<std::optional<SurfaceSpec>> given(objects.size());
    for (const NamedSurface& s : lines) given[index.at(s.object, fmt::format("{}:{}", source, s.line))] = s.spec;
    std::vector<SurfaceSpec> out(objects.size());
    for (std::size_t k = 0; k < objects.size(); ++k) {
        if (given[k]) {
            out[k] = *given[k];
        } else if (fallback) {
            out[k] = *fallback;
        } else {
            throw InputError(fmt::format("{}: object '{}' of the scene is not listed; add a line for it, or give "
                                         "--default-surface EMISSIVITY,TEMPERATURE",
                                         source, objects[k]));
        }
    }
    return out;
}

void validate(const RadiateOptions& o) {
    if (o.sky_temperature) check_temperature(*o.sky_temperature, "--sky-temperature");
    if (!(o.tolerance > 0.0 && o.tolerance < 1.0))
        throw InputError(fmt::format("radiation tolerance {}: must be in (0, 1)", o.tolerance));
    if (o.max_iterations < 1) throw InputError("radiation max iterations: must be >= 1");
    if (o.restart < 1 || o.restart > 1000) throw InputError(fmt::format("GMRES restart {}: must be 1..1000", o.restart));
    if (!(o.open_threshold >= 0.0 && o.open_threshold < 1.0))
        throw InputError(fmt::format("open threshold {}: must be in [0, 1)", o.open_threshold));
}

namespace radiate_detail {

double prepare_radiation(const RowProduct& F, std::span<const double> area, std::span<const SurfaceSpec> spec,
                         const RadiateOptions& options, RadiateResult& r) {
    validate(options);
    check_sizes(F, area.size(), spec.size(), "surface specs");
    const std::uint32_t n = F.size();
    const auto name = [&](std::uint32_t i) {
        return options.patch_name ? options.patch_name(i) : fmt::format("patch {}", i);
    };
    bool any_temperature = false;
    double total_area = 0.0;
    for (std::uint32_t i = 0; i < n; ++i) {
        if (!(area[i] > 0.0 && std::isfinite(area[i])))
            throw InputError(fmt::format("{}: area {} must be finite and > 0", name(i), area[i]));
        check_emissivity(spec[i].emissivity, name(i));
        if (spec[i].condition == SurfaceCondition::Temperature) {
            check_temperature(spec[i].value, name(i));
            any_temperature = true;
        } else if (!std::isfinite(spec[i].value)) {
            throw InputError(fmt::format("{}: heat flux {} must be finite", name(i), spec[i].value));
        }
        r.min_emissivity = std::min(r.min_emissivity, spec[i].emissivity);
        total_area += area[i];
    }
    r.sky_view = sky_view_factors(F);
    double mean_sky = 0.0, max_sky = 0.0;
    for (std::uint32_t i = 0; i < n; ++i) {
        mean_sky += area[i] * r.sky_view[i];
        max_sky = std::max(max_sky, r.sky_view[i]);
    }
    mean_sky = n ? mean_sky / total_area : 0.0;
    if (!options.sky_temperature && max_sky > options.open_threshold)
        throw InputError(fmt::format(
            "the scene is open: {:.4g}% of the hemisphere escapes on the area-weighted mean, up to {:.4g}% at {} "
            "(sky view factor above {:.3g}); give --sky-temperature T (K) for what the openings see",
            100.0 * mean_sky, 100.0 * max_sky,
            name(static_cast<std::uint32_t>(std::max_element(r.sky_view.begin(), r.sky_view.end()) - r.sky_view.begin())),
            options.open_threshold));
    if (!any_temperature && !options.sky_temperature)
        throw InputError("every surface has a given heat flux and there is no sky temperature: the temperatures are "
                         "then undetermined; give at least one surface a temperature");
    return options.sky_temperature ? emissive_power(*options.sky_temperature) : 0.0;
}

void finish_energy(RadiateResult& r, std::span<const double> area, double sky_power) {
    const std::size_t n = area.size();
    double abs_power = 0.0;
    for (std::size_t i = 0; i < n; ++i) {
        r.power += area[i] * r.heat_flux[i];
        abs_power += area[i] * std::abs(r.heat_flux[i]);
        r.sky += area[i] * r.sky_view[i] * (r.radiosity[i] - sky_power);
    }
    r.absolute_power = abs_power;
    const double scale = abs_power + std::abs(r.sky);
    r.balance_error = scale > 0.0 ? std::abs(r.power - r.sky) / scale : 0.0;
}

}  // namespace radiate_detail

void CsrRowProduct::multiply(std::span<const double> x, std::span<double> y) const {
    const std::uint32_t n = F_.size();
    const auto& ptr = F_.row_ptr();
    const auto& col = F_.col();
    const auto& val = F_.val();
    const auto rows = [&](std::uint32_t lo, std::uint32_t hi) {
        for (std::uint32_t i = lo; i < hi; ++i) {
            double s = 0.0;
            for (std::uint64_t k = ptr[i]; k < ptr[i + 1]; ++k) s += double(val[k]) * x[col[k]];
            y[i] = s;
        }
    };
    unsigned t = threads_ ? threads_ : std::max(1u, std::thread::hardware_concurrency());
    if (t <= 1 || F_.nnz() < 1000000) return rows(0, n);
    t = std::min(t, 64u);
    std::vector<std::uint32_t> cut(t + 1, n);
    cut[0] = 0;
    for (unsigned k = 1; k < t; ++k)
        cut[k] = static_cast<std::uint32_t>(std::lower_bound(ptr.begin(), ptr.begin() + n, F_.nnz() * k / t) - ptr.begin());
    std::vector<std::thread> pool;
    for (unsigned k = 1; k < t; ++k) pool.emplace_back([&, k] { rows(cut[k], std::max(cut[k], cut[k + 1])); });
    rows(0, cut[1]);
    for (std::thread& th : pool) th.join();
}

std::vector<double> CsrRowProduct::row_sums() const {
    if (F_.rows_filled() != F_.size())
        throw InputError(fmt::format("radiation: F has {} of its {} rows filled", F_.rows_filled(), F_.size()));
    std::vector<double> s(F_.size());
    for (std::uint32_t i = 0; i < F_.size(); ++i) s[i] = F_.row(i).sum();
    return s;
}

RadiateResult solve_radiation(const CsrMatrix& F, std::span<const double> area, std::span<const SurfaceSpec> spec,
                              const RadiateOptions& options) {
    return solve_radiation(CsrRowProduct(F, options.threads), area, spec, options);
}

ConductanceResult radiative_conductances(const CsrMatrix& F, std::span<const double> area,
                                         std::span<const double> emissivity, std::span<const std::uint32_t> object,
                                         std::uint32_t objects, const RadiateOptions& options) {
    return radiative_conductances(CsrRowProduct(F, options.threads), area, emissivity, object, objects, options);
}

RadiateResult solve_radiation(const RowProduct& F, std::span<const double> area, std::span<const SurfaceSpec> spec,
                              const RadiateOptions& options) {
    const auto t0 = std::chrono::steady_clock::now();
    RadiateResult r;
    const double sky_power = prepare_radiation(F, area, spec, options, r);
    const std::uint32_t n = F.size();

    // The system A J = b, A = I − diag(c) F (module docs).
    std::vector<double> c(n), b(n), j(n);
    for (std::uint32_t i = 0; i < n; ++i) {
        const SurfaceSpec& s = spec[i];
        const double sky_in = r.sky_view[i] * sky_power;  // σ T_sky⁴ F_sky,i: what the sky sends to i
        if (s.condition == SurfaceCondition::Temperature) {
            c[i] = 1.0 - s.emissivity;
            b[i] = s.emissivity * emissive_power(s.value) + c[i] * sky_in;
        } else {
            c[i] = 1.0;
            b[i] = s.value + sky_in;
        }
        j[i] = s.condition == SurfaceCondition::Temperature ? emissive_power(s.value) : b[i];
    }
    const ReflectionOperator op{F, c};
    const SolveOutcome solved = solve_reflections(op, b, j, options, "radiation");
    r.iterations = solved.iterations;
    r.residual = solved.residual;

    r.radiosity = j;
    r.irradiation.resize(n);
    op.gather(j, r.irradiation);
    r.heat_flux.resize(n);
    r.temperature.resize(n);
    for (std::uint32_t i = 0; i < n; ++i) {
        const SurfaceSpec& s = spec[i];
        double& g = r.irradiation[i];
        g += r.sky_view[i] * sky_power;
        if (s.condition == SurfaceCondition::Temperature) {
            // q = J − G with J = εσT⁴ + (1 − ε)G, i.e. q = ε (σT⁴ − G): the brief's ε/(1 − ε)(σT⁴ − J)
            // at convergence, without its 1/(1 − ε) amplification of J's error near ε = 1.
            r.temperature[i] = s.value;
            r.heat_flux[i] = s.emissivity * (emissive_power(s.value) - g);
        } else {
            // q = J − G and J = εσT⁴ + (1 − ε)G give σT⁴ = (J − (1 − ε)G)/ε = G + q/ε.
            r.heat_flux[i] = s.value;
            double e = g + s.value / s.emissivity;
            // Rounding of a solution converged to `tolerance` can make a true 0 slightly negative.
            const double slack = 10.0 * options.tolerance * (std::abs(g) + std::abs(s.value / s.emissivity));
            if (e < -slack)
                throw InputError(fmt::format(
                    "{}: the given heat flux {:.6g} W/m^2 leaving would need a temperature below 0 K (it receives "
                    "{:.6g} W/m^2 and can absorb at most emissivity x that, {:.6g} W/m^2)",
                    options.patch_name ? options.patch_name(i) : fmt::format("patch {}", i), s.value, g,
                    s.emissivity * g));
            e = std::max(e, 0.0);
            r.temperature[i] = std::pow(e / kStefanBoltzmann, 0.25);
        }
    }
    finish_energy(r, area, sky_power);
    r.seconds = seconds_since(t0);
    return r;
}

ConductanceResult radiative_conductances(const RowProduct& F, std::span<const double> area,
                                         std::span<const double> emissivity, std::span<const std::uint32_t> object,
                                         std::uint32_t objects, const RadiateOptions& options) {
    const auto t0 = std::chrono::steady_clock::now();
    validate(options);
    check_sizes(F, area.size(), emissivity.size(), "emissivities");
    check_sizes(F, area.size(), object.size(), "object indices");
    const std::uint32_t n = F.size();
    ConductanceResult r;
    r.gr.assign(objects, std::vector<double>(objects, 0.0));
    r.gr_sky.assign(objects, 0.0);
    r.emittance.assign(objects, 0.0);
    std::vector<double> c(n);
    for (std::uint32_t i = 0; i < n; ++i) {
        if (object[i] >= objects) throw InputError(fmt::format("patch {}: object {} out of range", i, object[i]));
        check_emissivity(emissivity[i], fmt::format("patch {}", i));
        c[i] = 1.0 - emissivity[i];
        r.emittance[object[i]] += emissivity[i] * area[i];
    }
    const std::vector<double> sky = sky_view_factors(F);
    const ReflectionOperator op{F, c};
    std::vector<double> b(n), j(n), g(n);
    for (std::uint32_t k = 0; k < objects; ++k) {
        if (!(r.emittance[k] > 0.0)) continue;
        // Unit blackbody exitance on k: E_i = ε_i σT⁴ with σT⁴ = 1 on k's patches; every patch
        // reflects (1 − ε) of what it receives: J = E + diag(1 − ε) F J.
        for (std::uint32_t i = 0; i < n; ++i) j[i] = b[i] = object[i] == k ? emissivity[i] : 0.0;
        const SolveOutcome solved = solve_reflections(op, b, j, options, fmt::format("conductances of object {}", k));
        r.iterations += solved.iterations;
        r.max_residual = std::max(r.max_residual, solved.residual);
        ++r.solves;
        op.gather(j, g);
        for (std::uint32_t i = 0; i < n; ++i) {
            r.gr[k][object[i]] += emissivity[i] * area[i] * g[i];  // absorbed by patch i
            r.gr_sky[k] += area[i] * sky[i] * j[i];                // leaving i to the sky
        }
    }
    double largest = 0.0;
    for (std::uint32_t k = 0; k < objects; ++k) {
        if (!(r.emittance[k] > 0.0)) continue;
        double sum = r.gr_sky[k];
        for (std::uint32_t l = 0; l < objects; ++l) {
            sum += r.gr[k][l];
            largest = std::max(largest, r.gr[k][l]);
        }
        r.sum_rule_error = std::max(r.sum_rule_error, std::abs(sum / r.emittance[k] - 1.0));
    }
    for (std::uint32_t k = 0; k < objects; ++k)
        for (std::uint32_t l = k + 1; l < objects; ++l) {
            const double a = r.gr[k][l], bb = r.gr[l][k], m = std::max(a, bb);
            if (m > 1e-9 * largest) r.reciprocity_error = std::max(r.reciprocity_error, std::abs(a - bb) / m);
        }
    r.seconds = seconds_since(t0);
    return r;
}

}  // namespace ffcube
