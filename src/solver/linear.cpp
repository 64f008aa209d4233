#include "ffcube/solver/linear.hpp"

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

}  // namespace ffcube
