// Shortwave with reflections on the rows of F (solver/shortwave.hpp, docs/urban.md).
//
// The sweep. P = ρ ∘ (Q + R), R = Fᵀ P. Starting from R⁰ = 0, each sweep computes
//     P^m = ρ ∘ (Q + R^m),   R^{m+1} = Fᵀ P^m,
// which is the series of bounces (R^m holds the first m of them). In the L1 norm one sweep
// multiplies the change by at most c = max_j Σ_i ρ_i F_ji < 1, so it converges for every albedo
// below 1 whatever F's reciprocity.
//
// The balance. After the last sweep (R = R^{M}, P^{M−1} the reflections that made it), the answer is
// absorbed_i = (1 − ρ_i)(Q_i + R_i) and P_i = ρ_i (Q_i + R_i), escaped = Σ_j P_j e_j with
// e_j = 1 − Σ_i F_ji. Then
//     Σ absorbed + escaped − Σ Q = Σ_i R_i − Σ_j P_j Σ_i F_ji = Σ_j (P^{M−1}_j − P_j) Σ_i F_ji,
// and |P^{M−1}_j − P_j| = ρ_j |R^{M−1}_j − R^M_j|: the balance error is at most the last sweep's
// change Σ|ΔR| (times max ρ·row sum < 1). The stopping rule bounds that change relative to Σ Q.
//
// Threads work on fixed blocks of rows (each row of Fᵀ by one thread, in column order), and the
// change is summed over the blocks in order: the same result for every thread count.
#include "ffcube/solver/shortwave.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <set>
#include <thread>

#include "ffcube/core/error.hpp"
#include "ffcube/solver/csv_fields.hpp"

namespace ffcube {
namespace {

constexpr std::uint32_t kBlockRows = 512;

// Runs body(first, last, block) over the blocks of kBlockRows rows, on `threads` threads (static
// assignment: block b by thread b mod threads).
template <class Body>
void for_blocks(std::uint32_t n, unsigned threads, const Body& body) {
    const std::uint32_t blocks = (n + kBlockRows - 1) / kBlockRows;
    const auto run = [&](unsigned t, unsigned stride) {
        for (std::uint32_t b = t; b < blocks; b += stride)
            body(b * kBlockRows, std::min(n, (b + 1) * kBlockRows), b);
    };
    const unsigned used = std::max(1u, std::min<unsigned>(threads, blocks));
    if (used <= 1) {
        run(0, 1);
        return;
    }
    std::vector<std::thread> pool;
    for (unsigned t = 1; t < used; ++t) pool.emplace_back(run, t, used);
    run(0, used);
    for (std::thread& th : pool) th.join();
}

}  // namespace

ShortwaveSystem make_shortwave_system(const CsrMatrix& F, std::vector<double> albedo,
                                      const std::function<std::string(std::uint32_t)>& patch_name) {
    const std::uint32_t n = F.size();
    if (F.rows_filled() != n) throw InternalError("make_shortwave_system: F has rows missing");
    if (albedo.size() != n)
        throw InternalError(fmt::format("make_shortwave_system: {} albedos for {} patches", albedo.size(), n));
    for (std::uint32_t i = 0; i < n; ++i)
        if (!(albedo[i] >= 0.0 && albedo[i] < 1.0))
            throw InputError(fmt::format("{}: albedo {} must be in [0, 1)", patch_name(i), albedo[i]));
    ShortwaveSystem s;
    s.n = n;
    // Transpose: count per column, then fill in row order (so each row of Fᵀ has j increasing).
    s.t_ptr.assign(std::size_t(n) + 1, 0);
    for (const std::uint32_t j : F.col()) ++s.t_ptr[j + 1];
    for (std::uint32_t i = 0; i < n; ++i) s.t_ptr[i + 1] += s.t_ptr[i];
    s.t_col.resize(F.nnz());
    s.t_val.resize(F.nnz());
    std::vector<std::uint64_t> next(s.t_ptr.begin(), s.t_ptr.end() - 1);
    s.escape.assign(n, 1.0);
    std::vector<double> weighted(n, 0.0);  // Σ_i ρ_i F_ji
    for (std::uint32_t j = 0; j < n; ++j) {
        const RowView r = F.row(j);
        double sum = 0.0;
        for (std::size_t k = 0; k < r.col.size(); ++k) {
            const std::uint32_t i = r.col[k];
            s.t_col[next[i]] = j;
            s.t_val[next[i]] = r.val[k];
            ++next[i];
            sum += static_cast<double>(r.val[k]);
            weighted[j] += albedo[i] * static_cast<double>(r.val[k]);
        }
        s.escape[j] = 1.0 - sum;
    }
    std::uint32_t worst = 0;
    for (std::uint32_t j = 0; j < n; ++j)
        if (weighted[j] > weighted[worst]) worst = j;
    s.contraction = n > 0 ? weighted[worst] : 0.0;
    if (!(s.contraction < 1.0))
        throw InputError(fmt::format("{}: the albedo-weighted sum of its row of F is {:.6g} >= 1 (row sum {:.6g}): the "
                                     "reflections would not converge; F is not a form-factor matrix of this scene",
                                     patch_name(worst), s.contraction, 1.0 - s.escape[worst]));
    s.albedo = std::move(albedo);
    return s;
}

ShortwaveSolution solve_shortwave(const ShortwaveSystem& s, std::span<const double> incident, std::uint32_t k,
                                  const ShortwaveControl& control) {
    const std::uint32_t n = s.n;
    if (incident.size() != std::size_t(n) * k)
        throw InternalError(fmt::format("solve_shortwave: {} values for {} patches x {} right-hand sides", incident.size(), n, k));
    const unsigned threads = control.threads > 0 ? control.threads : std::max(1u, std::thread::hardware_concurrency());
    ShortwaveSolution out;
    out.k = k;
    const std::size_t nk = std::size_t(n) * k;
    std::vector<double> total(k, 0.0);
    for (std::uint32_t i = 0; i < n; ++i)
        for (std::uint32_t c = 0; c < k; ++c) total[c] += incident[std::size_t(i) * k + c];

    std::vector<double> R(nk, 0.0), next(nk, 0.0), P(nk, 0.0);
    const std::uint32_t blocks = (n + kBlockRows - 1) / kBlockRows;
    std::vector<double> block_change(std::size_t(blocks) * k, 0.0);
    const auto reflect = [&](std::uint32_t first, std::uint32_t last) {  // P = ρ (Q + R)
        for (std::size_t x = std::size_t(first) * k; x < std::size_t(last) * k; ++x) P[x] = s.albedo[x / k] * (incident[x] + R[x]);
    };
    bool converged = false;
    while (!converged) {
        if (out.iterations >= control.max_iterations)
            throw NotConvergedError(fmt::format("shortwave reflections: {} sweeps without reaching the tolerance {:g} "
                                                "(last change {:.3g}; contraction {:.6g})",
                                                out.iterations, control.tolerance, out.change, s.contraction));
        for_blocks(n, threads, [&](std::uint32_t first, std::uint32_t last, std::uint32_t) { reflect(first, last); });
        for_blocks(n, threads, [&](std::uint32_t first, std::uint32_t last, std::uint32_t b) {
            double* change = block_change.data() + std::size_t(b) * k;
            std::fill(change, change + k, 0.0);
            for (std::uint32_t i = first; i < last; ++i) {
                double* y = next.data() + std::size_t(i) * k;
                std::fill(y, y + k, 0.0);
                for (std::uint64_t e = s.t_ptr[i]; e < s.t_ptr[i + 1]; ++e) {
                    const double v = s.t_val[e];
                    const double* p = P.data() + std::size_t(s.t_col[e]) * k;
                    for (std::uint32_t c = 0; c < k; ++c) y[c] += v * p[c];
                }
                const double* r = R.data() + std::size_t(i) * k;
                for (std::uint32_t c = 0; c < k; ++c) change[c] += std::abs(y[c] - r[c]);
            }
        });
        R.swap(next);
        ++out.iterations;
        converged = true;
        out.change = 0.0;
        for (std::uint32_t c = 0; c < k; ++c) {
            double sum = 0.0;
            for (std::uint32_t b = 0; b < blocks; ++b) sum += block_change[std::size_t(b) * k + c];
            const double rel = total[c] > 0.0 ? sum / total[c] : 0.0;
            if (!std::isfinite(rel))
                throw NotConvergedError("shortwave reflections: a value became infinite or NaN (incident power not finite?)");
            out.change = std::max(out.change, rel);
            if (rel > control.tolerance) converged = false;
        }
    }
    out.reflected = R;
    out.absorbed.resize(nk);
    out.escaped.assign(k, 0.0);
    for (std::uint32_t i = 0; i < n; ++i)
        for (std::uint32_t c = 0; c < k; ++c) {
            const std::size_t x = std::size_t(i) * k + c;
            const double arriving = incident[x] + R[x];
            out.absorbed[x] = (1.0 - s.albedo[i]) * arriving;
            out.escaped[c] += s.albedo[i] * arriving * s.escape[i];
        }
    return out;
}

std::vector<SunStep> parse_sun_series(std::string_view text, const std::string& source) {
    static const std::vector<std::string> kAngles = {"time", "azimuth", "elevation", "direct_normal_irradiance",
                                                      "diffuse_horizontal_irradiance"};
    static const std::vector<std::string> kVector = {"time", "sun_x", "sun_y", "sun_z", "direct_normal_irradiance",
                                                      "diffuse_horizontal_irradiance"};
    std::vector<SunStep> out;
    std::map<std::string, std::size_t> seen;
    const std::vector<std::string>* header = nullptr;
    std::size_t line_no = 0;
    if (text.substr(0, 3) == "\xEF\xBB\xBF") text.remove_prefix(3);
    while (!text.empty()) {
        const std::size_t nl = text.find('\n');
        const std::string_view line = trim(text.substr(0, nl));
        text = nl == std::string_view::npos ? std::string_view{} : text.substr(nl + 1);
        ++line_no;
        if (line.empty() || line.front() == '#') continue;
        const std::string where = fmt::format("{}:{}", source, line_no);
        const std::vector<std::string> f = split_csv(line, where);
        if (!header) {
            if (f == kAngles)
                header = &kAngles;
            else if (f == kVector)
                header = &kVector;
            else
                throw InputError(fmt::format("{}: the first line must be the header "
                                             "'time,azimuth,elevation,direct_normal_irradiance,diffuse_horizontal_irradiance' "
                                             "or 'time,sun_x,sun_y,sun_z,direct_normal_irradiance,diffuse_horizontal_irradiance'",
                                             where));
            continue;
        }
        if (f.size() != header->size())
            throw InputError(fmt::format("{}: {} fields; each line has the header's {}", where, f.size(), header->size()));
        SunStep s;
        s.line = line_no;
        s.time = f[0];
        if (s.time.empty()) throw InputError(fmt::format("{}: the time is empty", where));
        if (const auto it = seen.find(s.time); it != seen.end())
            throw InputError(fmt::format("{}: time '{}' is listed again (first on line {})", where, s.time, it->second));
        std::vector<double> v;
        for (std::size_t c = 1; c < f.size(); ++c) {
            const std::optional<double> x = parse_number(f[c], (*header)[c], where);
            if (!x) throw InputError(fmt::format("{}: {} is missing", where, (*header)[c]));
            v.push_back(*x);
        }
        if (header == &kAngles) {
            const double az = v[0], el = v[1];
            if (el < -90.0 || el > 90.0) throw InputError(fmt::format("{}: elevation {} must be in [-90, 90] degrees", where, el));
            const double a = az * M_PI / 180.0, e = el * M_PI / 180.0;
            s.x = std::sin(a) * std::cos(e);
            s.y = std::cos(a) * std::cos(e);
            s.z = std::sin(e);
            v.erase(v.begin(), v.begin() + 2);
        } else {
            const double len = std::sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
            if (!(len > 0.0) || !std::isfinite(len))
                throw InputError(fmt::format("{}: the direction towards the sun must not be zero", where));
            s.x = v[0] / len, s.y = v[1] / len, s.z = v[2] / len;
            v.erase(v.begin(), v.begin() + 3);
        }
        s.elevation = std::asin(std::clamp(s.z, -1.0, 1.0)) * 180.0 / M_PI;
        s.dni = v[0], s.dhi = v[1];
        if (!(s.dni >= 0.0)) throw InputError(fmt::format("{}: direct_normal_irradiance {} must be >= 0 (W/m^2)", where, s.dni));
        if (!(s.dhi >= 0.0))
            throw InputError(fmt::format("{}: diffuse_horizontal_irradiance {} must be >= 0 (W/m^2)", where, s.dhi));
        seen.emplace(s.time, line_no);
        out.push_back(std::move(s));
    }
    if (!header)
        throw InputError(fmt::format("{}: empty; expected the header "
                                     "'time,azimuth,elevation,direct_normal_irradiance,diffuse_horizontal_irradiance'",
                                     source));
    if (out.empty()) throw InputError(fmt::format("{}: no steps after the header", source));
    return out;
}

std::vector<double> parse_albedo_csv(std::string_view text, const std::string& source, const std::vector<std::string>& objects) {
    std::map<std::string, std::size_t> index;
    for (std::size_t k = 0; k < objects.size(); ++k) index.emplace(objects[k], k);
    std::vector<double> albedo(objects.size(), -1.0);
    std::vector<std::size_t> where_line(objects.size(), 0);
    bool header = false;
    std::size_t line_no = 0;
    if (text.substr(0, 3) == "\xEF\xBB\xBF") text.remove_prefix(3);
    while (!text.empty()) {
        const std::size_t nl = text.find('\n');
        const std::string_view line = trim(text.substr(0, nl));
        text = nl == std::string_view::npos ? std::string_view{} : text.substr(nl + 1);
        ++line_no;
        if (line.empty() || line.front() == '#') continue;
        const std::string where = fmt::format("{}:{}", source, line_no);
        const std::vector<std::string> f = split_csv(line, where);
        if (!header) {
            if (f != std::vector<std::string>{"object", "albedo"})
                throw InputError(fmt::format("{}: the first line must be the header 'object,albedo'", where));
            header = true;
            continue;
        }
        if (f.size() != 2) throw InputError(fmt::format("{}: {} fields; each line is object,albedo (2 fields)", where, f.size()));
        const auto it = index.find(f[0]);
        if (it == index.end()) throw InputError(fmt::format("{}: the scene has no object '{}'", where, f[0]));
        if (where_line[it->second] != 0)
            throw InputError(
                fmt::format("{}: object '{}' is listed again (first on line {})", where, f[0], where_line[it->second]));
        const std::optional<double> a = parse_number(f[1], "albedo", where);
        if (!a) throw InputError(fmt::format("{}: the albedo of '{}' is missing", where, f[0]));
        if (!(*a >= 0.0 && *a < 1.0))
            throw InputError(fmt::format("{}: albedo {} of '{}' must be in [0, 1) (a perfect reflector, 1, would keep "
                                         "reflecting in a closed street canyon)",
                                         where, *a, f[0]));
        albedo[it->second] = *a;
        where_line[it->second] = line_no;
    }
    if (!header) throw InputError(fmt::format("{}: empty; expected the header 'object,albedo'", source));
    std::vector<std::string> missing;
    for (std::size_t k = 0; k < objects.size(); ++k)
        if (where_line[k] == 0) missing.push_back(objects[k]);
    if (!missing.empty())
        throw InputError(fmt::format("{}: {} of the scene's {} objects have no albedo, e.g. '{}'", source, missing.size(),
                                     objects.size(), missing.front()));
    return albedo;
}

}  // namespace ffcube
