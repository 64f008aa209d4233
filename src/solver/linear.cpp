#include "ffcube/solver/linear.hpp"

#include <algorithm>
#include <cmath>
#include <numeric>
#include <utility>

#include <fmt/format.h>

#include "ffcube/core/error.hpp"

namespace ffcube {

void lu_factor(DenseMatrix& a, std::vector<std::uint32_t>& perm, const char* what) {
    const std::uint32_t n = a.size();
    perm.resize(n);
    std::iota(perm.begin(), perm.end(), 0u);
    for (std::uint32_t k = 0; k < n; ++k) {
        // Partial pivoting: the largest |a_ik| below the diagonal bounds the multipliers by 1.
        std::uint32_t p = k;
        for (std::uint32_t i = k + 1; i < n; ++i)
            if (std::abs(a(i, k)) > std::abs(a(p, k))) p = i;
        if (a(p, k) == 0.0)
            throw InputError(fmt::format("{}: the matrix is singular (no non-zero pivot in column {})", what, k));
        if (p != k) {
            std::swap_ranges(a.row(k).begin(), a.row(k).end(), a.row(p).begin());
            std::swap(perm[k], perm[p]);
        }
        const std::span<const double> pivot_row = a.row(k);
        const double inv = 1.0 / pivot_row[k];
        for (std::uint32_t i = k + 1; i < n; ++i) {
            const std::span<double> r = a.row(i);
            const double m = r[k] * inv;
            r[k] = m;
            if (m == 0.0) continue;  // sparse rows of ρF: most of the update would add zeros
            // Row-wise update keeps the inner loop contiguous in memory.
            for (std::uint32_t j = k + 1; j < n; ++j) r[j] -= m * pivot_row[j];
        }
    }
}

void lu_solve(const DenseMatrix& lu, std::span<const std::uint32_t> perm, std::span<double> b,
              std::span<double> scratch) {
    const std::uint32_t n = lu.size();
    for (std::uint32_t i = 0; i < n; ++i) scratch[i] = b[perm[i]];
    for (std::uint32_t i = 0; i < n; ++i) {  // L y = P b, unit diagonal
        const std::span<const double> r = lu.row(i);
        double s = scratch[i];
        for (std::uint32_t j = 0; j < i; ++j) s -= r[j] * scratch[j];
        scratch[i] = s;
    }
    for (std::uint32_t i = n; i-- > 0;) {  // U x = y
        const std::span<const double> r = lu.row(i);
        double s = scratch[i];
        for (std::uint32_t j = i + 1; j < n; ++j) s -= r[j] * scratch[j];
        scratch[i] = s / r[i];
    }
    std::copy(scratch.begin(), scratch.begin() + n, b.begin());
}

GmresOutcome gmres(const LinearOperator& a, std::span<const double> b, std::span<double> x, const GmresControl& c,
                   const std::function<double(std::span<const double> r)>& measure) {
    const std::size_t n = b.size();
    const std::uint32_t m = std::max<std::uint32_t>(1, c.restart);
    GmresOutcome out;
    std::vector<double> r(n), w(n);
    std::vector<std::vector<double>> v(m + 1, std::vector<double>(n));
    std::vector<double> h(std::size_t(m + 1) * m), cs(m), sn(m), g(m + 1), y(m);
    const auto H = [&](std::uint32_t i, std::uint32_t j) -> double& { return h[std::size_t(i) * m + j]; };
    const auto dot = [&](std::span<const double> p, std::span<const double> q) {
        double s = 0.0;
        for (std::size_t i = 0; i < n; ++i) s += p[i] * q[i];
        return s;
    };
    const auto true_residual = [&] {
        a(x, r);
        ++out.iterations;
        for (std::size_t i = 0; i < n; ++i) r[i] = b[i] - r[i];
        out.measure = measure(r);
    };
    true_residual();
    int stagnant = 0;
    while (true) {
        if (!std::isfinite(out.measure)) {
            out.stagnated = true;
            return out;
        }
        if (out.measure <= c.tolerance) {
            out.converged = true;
            return out;
        }
        if (out.iterations >= c.max_iterations) return out;
        const double start = out.measure;
        const double beta = std::sqrt(dot(r, r));
        if (!(beta > 0.0)) {  // measure says not converged, yet r = 0: the measure is the caller's own
            out.stagnated = true;
            return out;
        }
        for (std::size_t i = 0; i < n; ++i) v[0][i] = r[i] / beta;
        std::fill(g.begin(), g.end(), 0.0);
        g[0] = beta;
        std::uint32_t k = 0;
        while (k < m && out.iterations < c.max_iterations) {
            a(v[k], w);
            ++out.iterations;
            for (std::uint32_t i = 0; i <= k; ++i) {  // modified Gram–Schmidt
                H(i, k) = dot(w, v[i]);
                for (std::size_t j = 0; j < n; ++j) w[j] -= H(i, k) * v[i][j];
            }
            const double norm = std::sqrt(dot(w, w));
            H(k + 1, k) = norm;
            for (std::uint32_t i = 0; i < k; ++i) {  // earlier rotations on the new column
                const double t = cs[i] * H(i, k) + sn[i] * H(i + 1, k);
                H(i + 1, k) = -sn[i] * H(i, k) + cs[i] * H(i + 1, k);
                H(i, k) = t;
            }
            const double d = std::hypot(H(k, k), H(k + 1, k));
            cs[k] = d > 0.0 ? H(k, k) / d : 1.0;
            sn[k] = d > 0.0 ? H(k + 1, k) / d : 0.0;
            H(k, k) = d;
            H(k + 1, k) = 0.0;
            g[k + 1] = -sn[k] * g[k];
            g[k] = cs[k] * g[k];
            ++k;
            if (!(norm > 0.0) || std::abs(g[k]) <= c.inner_tolerance) break;  // happy breakdown or small enough
            for (std::size_t j = 0; j < n; ++j) v[k][j] = w[j] / norm;
        }
        // x += V y with H y = g (upper triangular k × k).
        for (std::uint32_t i = k; i-- > 0;) {
            double s = g[i];
            for (std::uint32_t j = i + 1; j < k; ++j) s -= H(i, j) * y[j];
            y[i] = H(i, i) != 0.0 ? s / H(i, i) : 0.0;
        }
        for (std::uint32_t j = 0; j < k; ++j)
            for (std::size_t i = 0; i < n; ++i) x[i] += y[j] * v[j][i];
        true_residual();
        stagnant = out.measure < c.stagnation * start ? 0 : stagnant + 1;
        if (stagnant >= 2 && !(out.measure <= c.tolerance)) {
            out.stagnated = true;
            return out;
        }
    }
}

}  // namespace ffcube
