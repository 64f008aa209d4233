// Reciprocity and closure enforcement.
#include "ffcube/accuracy/enforce.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <tuple>

#include "ffcube/core/error.hpp"

namespace ffcube {

EnforceMode parse_enforce_mode(const std::string& name) {
    if (name == "reciprocity") return EnforceMode::Reciprocity;
    if (name == "closure" || name == "both") return EnforceMode::Closure;
    throw InputError(fmt::format("--enforce {}: must be reciprocity, closure or both", name));
}

void require_closed_scene(std::string_view what, const ClosureEvidence& evidence, const CsrMatrix& F) {
    if (evidence.hemicube_miss_weight > 0)
        throw InputError(fmt::format(
            "--enforce {}: hemicube pixels saw nothing (ΔF {:.3g} summed over hemicubes): the scene is open (light "
            "escapes), and closure would hide that",
            what, evidence.hemicube_miss_weight));
    if (!std::isnan(evidence.inner_row_sum_min)) {
        if (evidence.inner_row_sum_min < 1.0 - 1e-3)
            throw InputError(fmt::format("--enforce {}: a row sums to {:.6g} < 1 - 0.001 before correction: the scene "
                                         "is open (light escapes), and closure would hide that",
                                         what, evidence.inner_row_sum_min));
        return;
    }
    require_closed(F, 1e-3);
}

double EnforcedMatrix::at(std::uint32_t i, std::uint32_t j) const {
    const auto b = col.begin() + static_cast<long>(row_ptr[i]), e = col.begin() + static_cast<long>(row_ptr[i + 1]);
    const auto it = std::lower_bound(b, e, j);
    return it != e && *it == j ? val[static_cast<std::size_t>(it - col.begin())] : 0.0;
}

double EnforcedMatrix::row_sum(std::uint32_t i) const {
    double s = 0;
    for (std::uint64_t k = row_ptr[i]; k < row_ptr[i + 1]; ++k) s += val[k];
    return s;
}

CsrMatrix EnforcedMatrix::to_csr() const {
    std::vector<float> v(val.size());
    for (std::size_t k = 0; k < val.size(); ++k) v[k] = static_cast<float>(val[k]);
    return CsrMatrix::from_arrays(n, row_ptr, col, std::move(v));
}

MatrixFigures matrix_figures(const EnforcedMatrix& F, std::span<const double> areas) {
    MatrixFigures f;
    f.row_sum_min = INFINITY;
    f.row_sum_max = -INFINITY;
    // F_ji by a cursor per row j (rows visited with i increasing: see reciprocity_stats).
    std::vector<std::uint64_t> cursor(F.row_ptr.begin(), F.row_ptr.end() - 1);
    for (std::uint32_t i = 0; i < F.n; ++i) {
        const double s = F.row_sum(i);
        f.row_sum_min = std::min(f.row_sum_min, s);
        f.row_sum_max = std::max(f.row_sum_max, s);
        for (std::uint64_t k = F.row_ptr[i]; k < F.row_ptr[i + 1]; ++k) {
            const std::uint32_t j = F.col[k];
            std::uint64_t& c = cursor[j];
            while (c < F.row_ptr[j + 1] && F.col[c] < i) ++c;
            const double fji = c < F.row_ptr[j + 1] && F.col[c] == i ? F.val[c] : 0.0;
            const double dev = std::abs(areas[i] * F.val[k] - areas[j] * fji) / ((areas[i] + areas[j]) / 2);
            f.reciprocity_max = std::max(f.reciprocity_max, dev);
        }
    }
    if (F.n == 0) f.row_sum_min = f.row_sum_max = 0;
    return f;
}

void require_closed(const CsrMatrix& F, double tolerance) {
    for (std::uint32_t i = 0; i < F.size(); ++i) {
        const double s = F.row(i).sum();
        if (s < 1.0 - tolerance)
            throw InputError(fmt::format(
                "--enforce closure: row {} sums to {:.6g} < 1 - {:g}: the scene is open (light escapes), and closure "
                "would hide that",
                i, s, tolerance));
    }
}

EnforcedMatrix enforce(const CsrMatrix& F, std::span<const double> areas, EnforceMode mode, EnforceStats& stats) {
    const std::uint32_t n = F.size();
    if (areas.size() != n) throw InputError(fmt::format("--enforce: {} areas for {} rows", areas.size(), n));
    for (std::uint32_t i = 0; i < n; ++i)
        if (!(areas[i] > 0)) throw InputError(fmt::format("--enforce: patch {} has area {} (must be > 0)", i, areas[i]));

    EnforcedMatrix in;
    in.n = n;
    in.row_ptr.assign(F.row_ptr().begin(), F.row_ptr().end());
    in.col = F.col();
    in.val.assign(F.val().begin(), F.val().end());
    stats.before = matrix_figures(in, areas);

    // G = (A F + (A F)ᵀ) / 2 on the union pattern: each entry contributes half to (i,j) and (j,i).
    std::vector<std::tuple<std::uint32_t, std::uint32_t, double>> t;
    t.reserve(2 * in.val.size());
    for (std::uint32_t i = 0; i < n; ++i)
        for (std::uint64_t k = in.row_ptr[i]; k < in.row_ptr[i + 1]; ++k) {
            const double g = areas[i] * in.val[k] / 2;
            t.emplace_back(i, in.col[k], g);
            t.emplace_back(in.col[k], i, g);
        }
    std::sort(t.begin(), t.end(), [](const auto& a, const auto& b) {
        return std::get<0>(a) != std::get<0>(b) ? std::get<0>(a) < std::get<0>(b) : std::get<1>(a) < std::get<1>(b);
    });
    EnforcedMatrix G;
    G.n = n;
    G.row_ptr.assign(n + 1, 0);
    for (std::size_t k = 0; k < t.size();) {
        const std::uint32_t i = std::get<0>(t[k]), j = std::get<1>(t[k]);
        double g = 0;
        // Sum in sorted order (deterministic).
        for (; k < t.size() && std::get<0>(t[k]) == i && std::get<1>(t[k]) == j; ++k) g += std::get<2>(t[k]);
        G.col.push_back(j);
        G.val.push_back(g);
        ++G.row_ptr[i + 1];
    }
    for (std::uint32_t i = 0; i < n; ++i) G.row_ptr[i + 1] += G.row_ptr[i];

    std::vector<double> d(n, 1.0);
    if (mode == EnforceMode::Closure) {
        for (std::uint32_t i = 0; i < n; ++i)
            if (G.row_ptr[i + 1] == G.row_ptr[i])
                throw InputError(fmt::format("--enforce closure: patch {} neither sees nor is seen by any patch", i));
        std::vector<double> gd(n);
        constexpr unsigned kMaxIterations = 100000;
        constexpr double kTarget = 1e-12;  // max |row sum − 1|
        unsigned it = 0;
        for (;; ++it) {
            double worst = 0;
            for (std::uint32_t i = 0; i < n; ++i) {
                double s = 0;
                for (std::uint64_t k = G.row_ptr[i]; k < G.row_ptr[i + 1]; ++k) s += G.val[k] * d[G.col[k]];
                gd[i] = s;
                worst = std::max(worst, std::abs(d[i] * s / areas[i] - 1.0));
            }
            if (worst <= kTarget) break;
            if (it == kMaxIterations)
                throw InputError(fmt::format(
                    "--enforce closure: no symmetric scaling reaches row sums of 1 (still {:.3g} off after {} iterations)",
                    worst, it));
            // Jacobi-style update from the sums of the previous iterate: deterministic and symmetric.
            for (std::uint32_t i = 0; i < n; ++i) d[i] = std::sqrt(d[i] * areas[i] / gd[i]);
        }
        stats.iterations = it;
    }
    EnforcedMatrix out = G;
    for (std::uint32_t i = 0; i < n; ++i)
        for (std::uint64_t k = out.row_ptr[i]; k < out.row_ptr[i + 1]; ++k)
            out.val[k] = d[i] * G.val[k] * d[out.col[k]] / areas[i];
    stats.after = matrix_figures(out, areas);
    return out;
}

}  // namespace ffcube
