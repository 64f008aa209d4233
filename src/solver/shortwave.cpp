// Shortwave with reflections on the rows of F (solver/shortwave.hpp, docs/urban.md).
//
// The sweeps. P = ρ ∘ (Q + R), R = Fᵀ P. Starting from P = ρ ∘ Q (R = 0), Gauss–Seidel sweeps
// over the rows of Fᵀ in order: R_i = Σ_j F_ji P_j with the P_j of this sweep where already
// updated, then P_i = ρ_i (Q_i + R_i). The system I − ρ∘Fᵀ is an M-matrix whose Jacobi sweep (the
// series of bounces) contracts by c = max_j Σ_i ρ_i F_ji < 1 in the L1 norm, so Gauss–Seidel
// converges too (Stein–Rosenberg), about twice as fast, for every albedo below 1 whatever F's
// reciprocity.
//
// The balance. After the sweeps (P from them), one last product R' = Fᵀ P gives the answer:
// absorbed_i = (1 − ρ_i)(Q_i + R'_i), P'_i = ρ_i (Q_i + R'_i), escaped = Σ_j P'_j e_j with
// e_j = 1 − Σ_i F_ji. Then
//     Σ absorbed + escaped − Σ Q = Σ_i R'_i − Σ_j P'_j Σ_i F_ji = Σ_j (P_j − P'_j) Σ_i F_ji,
// and |P_j − P'_j| = ρ_j |R_j − R'_j|: the balance error is at most Σ|R − R'| (times max ρ·row
// sum < 1), that last product's change, which is of the order of the last sweep's. The stopping
// rule bounds the sweeps' change relative to Σ Q, and ShortwaveSolution::change reports the last
// product's.
//
// The right-hand sides are solved in groups of kGroup columns, each group on its own (its own
// sweeps and stopping rule, over all its columns) by one thread: a group's vectors (n × 4 doubles,
// 0.7 MB for 22,881 patches; half that in float) stay in cache while the rows of Fᵀ stream past,
// and no column's numbers depend on the thread count. (4 columns measured faster per CPU second
// than 2, 8 or 16 on the 22,881-facet city: tools/bench_shortwave_solve.)
#include "ffcube/solver/shortwave.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <exception>
#include <limits>
#include <map>
#include <thread>

#include "ffcube/core/csv_input.hpp"
#include "ffcube/core/error.hpp"

namespace ffcube {
namespace {

constexpr std::uint32_t kGroup = 4;  // columns (right-hand sides) a row of Fᵀ is applied to at once
// Sweeps read P rounded to float (relative error 6e-8) while they change R by more than this
// (relative to Σ Q): far above that rounding, so they still converge as in double.
constexpr double kFloatSweeps = 1e-5;
constexpr double kMaxIrradiance = 1e5;  // W/m², parse_sun_series

// y[0..kGroup) = Σ_e val[e] · P[col[e] · stride + 0..kGroup): one row of Fᵀ on one group of
// columns. Built for AVX2 (Haswell: with FMA) as well as the baseline, picked at run time. Each
// y[c] is summed in the same order in both, but GCC may fuse a·b + c into one FMA in the Haswell
// clone, so the last bits can differ between a machine with FMA and one without; on one machine
// they never depend on the thread count.
template <class T, class I>
#if defined(__x86_64__) && defined(__GNUC__) && !defined(__clang__)
__attribute__((target_clones("arch=haswell", "default")))
#endif
void row_times_group(const I* col, const float* val, std::uint64_t count, const T* P, std::size_t stride,
                     double* y) {
    double acc[kGroup] = {};
    for (std::uint64_t e = 0; e < count; ++e) {
        const double v = val[e];
        const T* p = P + std::size_t(col[e]) * stride;
        for (std::uint32_t c = 0; c < kGroup; ++c) acc[c] += v * static_cast<double>(p[c]);
    }
    for (std::uint32_t c = 0; c < kGroup; ++c) y[c] = acc[c];
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
    if (n <= 65536) {  // the sweeps stream the columns in 16 bits
        s.t_col16.assign(s.t_col.begin(), s.t_col.end());
        std::vector<std::uint32_t>().swap(s.t_col);
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

namespace {

struct GroupResult {
    std::uint32_t iterations = 0;
    double change = 0.0;
};

// Solves the kGroup columns [c0, c0 + kGroup) (those ≥ k are zero) on their own: Gauss–Seidel
// sweeps, then the last product; writes the columns of out.
GroupResult solve_group(const ShortwaveSystem& s, std::span<const double> incident, std::uint32_t k, std::uint32_t c0,
                        const ShortwaveControl& control, ShortwaveSolution& out) {
    const std::uint32_t n = s.n;
    const std::uint32_t width = std::min(kGroup, k - c0);
    std::vector<double> Q(std::size_t(n) * kGroup, 0.0), R(Q.size(), 0.0), P(Q.size(), 0.0);
    double total[kGroup] = {}, change[kGroup] = {};
    for (std::uint32_t i = 0; i < n; ++i)
        for (std::uint32_t c = 0; c < width; ++c) {
            const double q = incident[std::size_t(i) * k + c0 + c];
            Q[std::size_t(i) * kGroup + c] = q;
            P[std::size_t(i) * kGroup + c] = s.albedo[i] * q;
            total[c] += q;
        }
    const auto largest_change = [&] {
        double worst = 0.0;
        for (std::uint32_t c = 0; c < width; ++c) {
            const double rel = total[c] > 0.0 ? change[c] / total[c] : 0.0;
            if (!std::isfinite(rel))
                throw NotConvergedError("shortwave reflections: a value became infinite or NaN (incident power not finite?)");
            worst = std::max(worst, rel);
        }
        return worst;
    };
    GroupResult g;
    // One Gauss–Seidel sweep over the rows in order, in place: R_i = Σ_j F_ji P_j with the P_j
    // already updated, then P_i = ρ_i (Q_i + R_i); Σ_i |ΔR_i| per column. The first sweeps read a
    // float copy of P (half the memory traffic) until the change is below kFloatSweeps; the rest,
    // and the last product, read P itself (double).
    std::vector<float> Pf(P.size());
    for (std::size_t x = 0; x < P.size(); ++x) Pf[x] = static_cast<float>(P[x]);
    bool single = true;
    do {
        if (g.iterations >= control.max_iterations)
            throw NotConvergedError(fmt::format("shortwave reflections: {} sweeps without reaching the tolerance {:g} "
                                                "(last change {:.3g}; contraction {:.6g})",
                                                g.iterations, control.tolerance, g.change, s.contraction));
        std::fill(change, change + kGroup, 0.0);
        for (std::uint32_t i = 0; i < n; ++i) {
            double y[kGroup];
            const float* val = s.t_val.data() + s.t_ptr[i];
            const std::uint64_t count = s.t_ptr[i + 1] - s.t_ptr[i];
            if (!s.t_col16.empty()) {
                const std::uint16_t* col = s.t_col16.data() + s.t_ptr[i];
                if (single)
                    row_times_group(col, val, count, Pf.data(), kGroup, y);
                else
                    row_times_group(col, val, count, P.data(), kGroup, y);
            } else {
                const std::uint32_t* col = s.t_col.data() + s.t_ptr[i];
                if (single)
                    row_times_group(col, val, count, Pf.data(), kGroup, y);
                else
                    row_times_group(col, val, count, P.data(), kGroup, y);
            }
            const std::size_t x = std::size_t(i) * kGroup;
            for (std::uint32_t c = 0; c < kGroup; ++c) {
                change[c] += std::abs(y[c] - R[x + c]);
                R[x + c] = y[c];
                P[x + c] = s.albedo[i] * (Q[x + c] + y[c]);
                Pf[x + c] = static_cast<float>(P[x + c]);
            }
        }
        ++g.iterations;
        g.change = largest_change();
        if (single && g.change <= kFloatSweeps) {
            single = false;
            g.change = std::numeric_limits<double>::infinity();  // at least one sweep in double
        }
    } while (g.change > control.tolerance);
    // The answer from one last product with the P of the sweeps (the balance above): R' = Fᵀ P,
    // absorbed and escaped from P' = ρ (Q + R'). Its change bounds the balance error.
    std::fill(change, change + kGroup, 0.0);
    for (std::uint32_t i = 0; i < n; ++i) {
        double y[kGroup];
        if (!s.t_col16.empty())
            row_times_group(s.t_col16.data() + s.t_ptr[i], s.t_val.data() + s.t_ptr[i], s.t_ptr[i + 1] - s.t_ptr[i], P.data(),
                            kGroup, y);
        else
            row_times_group(s.t_col.data() + s.t_ptr[i], s.t_val.data() + s.t_ptr[i], s.t_ptr[i + 1] - s.t_ptr[i], P.data(),
                            kGroup, y);
        for (std::uint32_t c = 0; c < width; ++c) {
            const std::size_t x = std::size_t(i) * kGroup + c, o = std::size_t(i) * k + c0 + c;
            change[c] += std::abs(y[c] - R[x]);
            const double arriving = Q[x] + y[c];
            out.reflected[o] = y[c];
            out.absorbed[o] = (1.0 - s.albedo[i]) * arriving;
        }
    }
    ++g.iterations;
    g.change = largest_change();
    return g;
}

}  // namespace

ShortwaveSolution solve_shortwave(const ShortwaveSystem& s, std::span<const double> incident, std::uint32_t k,
                                  const ShortwaveControl& control) {
    const std::uint32_t n = s.n;
    if (incident.size() != std::size_t(n) * k)
        throw InternalError(fmt::format("solve_shortwave: {} values for {} patches x {} right-hand sides", incident.size(), n, k));
    const unsigned threads = control.threads > 0 ? control.threads : std::max(1u, std::thread::hardware_concurrency());
    ShortwaveSolution out;
    out.k = k;
    out.reflected.assign(std::size_t(n) * k, 0.0);
    out.absorbed.assign(std::size_t(n) * k, 0.0);
    // Groups of kGroup columns are independent solves: each thread takes whole groups (group g by
    // thread g mod threads), so no column's numbers depend on the thread count.
    const std::uint32_t groups = (k + kGroup - 1) / kGroup;
    std::vector<GroupResult> result(groups);
    std::vector<std::exception_ptr> failure(groups);
    const unsigned used = std::max(1u, std::min<unsigned>(threads, groups));
    const auto part = [&](unsigned t) {
        for (std::uint32_t g = t; g < groups; g += used) {
            try {
                result[g] = solve_group(s, incident, k, g * kGroup, control, out);
            } catch (...) {
                failure[g] = std::current_exception();
            }
        }
    };
    std::vector<std::thread> pool;
    for (unsigned t = 1; t < used; ++t) pool.emplace_back(part, t);
    part(0);
    for (std::thread& th : pool) th.join();
    for (const std::exception_ptr& e : failure)
        if (e) std::rethrow_exception(e);
    for (const GroupResult& g : result) {
        out.iterations = std::max(out.iterations, g.iterations);
        out.change = std::max(out.change, g.change);
    }
    out.escaped.assign(k, 0.0);
    for (std::uint32_t i = 0; i < n; ++i)
        for (std::uint32_t c = 0; c < k; ++c) {
            const std::size_t o = std::size_t(i) * k + c;
            out.escaped[c] += s.albedo[i] * (incident[o] + out.reflected[o]) * s.escape[i];
        }
    return out;
}

std::vector<SunStep> parse_sun_series(std::string_view text, const std::string& source) {
    static const std::vector<CsvHeader> kHeaders = {
        {"time", "azimuth", "elevation", "direct_normal_irradiance", "diffuse_horizontal_irradiance"},
        {"time", "sun_x", "sun_y", "sun_z", "direct_normal_irradiance", "diffuse_horizontal_irradiance"}};
    const CsvTable table = parse_csv(text, source, kHeaders);
    const bool angles = table.header_index == 0;
    std::vector<SunStep> out;
    std::map<std::string, std::size_t> seen;
    for (const CsvRow& row : table.rows) {
        SunStep s;
        s.line = row.line;
        s.time = row.fields[0];
        if (s.time.empty()) row.fail("the time is empty");
        if (const auto it = seen.find(s.time); it != seen.end())
            row.fail(fmt::format("time '{}' is listed again (first on line {})", s.time, it->second));
        std::vector<double> v;
        for (std::size_t c = 1; c < row.fields.size(); ++c) v.push_back(row.required(c));
        if (angles) {
            const double az = v[0], el = v[1];
            if (el < -90.0 || el > 90.0) row.fail(fmt::format("elevation {} must be in [-90, 90] degrees", el));
            const double a = az * M_PI / 180.0, e = el * M_PI / 180.0;
            s.x = std::sin(a) * std::cos(e);
            s.y = std::cos(a) * std::cos(e);
            s.z = std::sin(e);
            v.erase(v.begin(), v.begin() + 2);
        } else {
            const double len = std::sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
            if (!(len > 0.0) || !std::isfinite(len)) row.fail("the direction towards the sun must not be zero");
            s.x = v[0] / len, s.y = v[1] / len, s.z = v[2] / len;
            v.erase(v.begin(), v.begin() + 3);
        }
        s.elevation = std::asin(std::clamp(s.z, -1.0, 1.0)) * 180.0 / M_PI;
        s.dni = v[0], s.dhi = v[1];
        // At most kMaxIrradiance: 70 times the solar constant (1361 W/m²) is no sunlight, and keeps
        // every power of a city far from overflow.
        for (const auto& [value, name] : {std::pair{s.dni, "direct_normal_irradiance"}, {s.dhi, "diffuse_horizontal_irradiance"}})
            if (!(value >= 0.0 && value <= kMaxIrradiance))
                row.fail(fmt::format("{} {} must be in [0, {:g}] W/m^2", name, value, kMaxIrradiance));
        seen.emplace(s.time, row.line);
        out.push_back(std::move(s));
    }
    if (out.empty()) throw InputError(fmt::format("{}: no steps after the header", source));
    return out;
}

std::vector<double> parse_albedo_csv(std::string_view text, const std::string& source, const std::vector<std::string>& objects) {
    static const CsvHeader kHeader = {"object", "albedo"};
    const ObjectIndex index(objects);
    std::vector<double> albedo(objects.size(), -1.0);
    std::vector<std::size_t> where_line(objects.size(), 0);
    for (const CsvRow& row : parse_csv(text, source, std::span(&kHeader, 1)).rows) {
        const std::string& object = row.fields[0];
        const std::size_t k = index.at(object, row.where);
        if (where_line[k] != 0) row.fail(fmt::format("object '{}' is listed again (first on line {})", object, where_line[k]));
        const std::optional<double> a = row.number(1);
        if (!a) row.fail(fmt::format("the albedo of '{}' is missing", object));
        if (!(*a >= 0.0 && *a < 1.0))
            row.fail(fmt::format("albedo {} of '{}' must be in [0, 1) (a perfect reflector, 1, would keep reflecting in a "
                                 "closed street canyon)",
                                 *a, object));
        albedo[k] = *a;
        where_line[k] = row.line;
    }
    std::vector<std::string> missing;
    for (std::size_t k = 0; k < objects.size(); ++k)
        if (where_line[k] == 0) missing.push_back(objects[k]);
    if (!missing.empty())
        throw InputError(fmt::format("{}: {} of the scene's {} objects have no albedo, e.g. '{}'", source, missing.size(),
                                     objects.size(), missing.front()));
    return albedo;
}

}  // namespace ffcube
