// Reciprocity and closure enforcement.
#include "ffcube/accuracy/enforce.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <span>
#include <vector>

#include "ffcube/core/error.hpp"
#include "ffcube/core/progress.hpp"

namespace ffcube {

EnforceMode parse_enforce_mode(const std::string& name) {
    if (name == "reciprocity") return EnforceMode::Reciprocity;
    if (name == "closure" || name == "both") return EnforceMode::Closure;
    throw InputError(fmt::format("--enforce {}: must be reciprocity, closure or both", name));
}

namespace {

// The first row summing below 1 − tolerance, as require_closed() names it.
void require_rows_closed(std::span<const double> row_sums, double tolerance) {
    for (std::size_t i = 0; i < row_sums.size(); ++i)
        if (row_sums[i] < 1.0 - tolerance)
            throw InputError(fmt::format(
                "--enforce closure: row {} sums to {:.6g} < 1 - {:g}: the scene is open (light escapes), and closure "
                "would hide that",
                i, row_sums[i], tolerance));
}

// ClosureEvidence judged before F; true when F's own row sums are to be judged.
bool closure_needs_row_sums(std::string_view what, const ClosureEvidence& evidence) {
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
        return false;
    }
    return true;
}

// MatrixFigures over rows fed in order: matrix_figures()'s expressions, whose max and min do not
// depend on the order the pairs come in.
struct FigureSums {
    MatrixFigures f{INFINITY, -INFINITY, 0.0};
    std::uint32_t rows = 0;
    void row_sum(double s) {
        f.row_sum_min = std::min(f.row_sum_min, s);
        f.row_sum_max = std::max(f.row_sum_max, s);
        ++rows;
    }
    void pair(double ai, double fij, double aj, double fji) {
        f.reciprocity_max = std::max(f.reciprocity_max, std::abs(ai * fij - aj * fji) / ((ai + aj) / 2));
    }
    MatrixFigures figures() const {
        MatrixFigures r = f;
        if (rows == 0) r.row_sum_min = r.row_sum_max = 0;
        return r;
    }
};

}  // namespace

void require_closed_scene(std::string_view what, const ClosureEvidence& evidence, const CsrMatrix& F) {
    if (closure_needs_row_sums(what, evidence)) require_closed(F, 1e-3);
}

void require_closed_scene(std::string_view what, const ClosureEvidence& evidence, std::span<const double> row_sums) {
    if (closure_needs_row_sums(what, evidence)) require_rows_closed(row_sums, 1e-3);
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
    std::vector<double> sums(F.size());
    for (std::uint32_t i = 0; i < F.size(); ++i) sums[i] = F.row(i).sum();
    require_rows_closed(sums, tolerance);
}

void enforce_passes(std::uint32_t n, std::span<const double> areas, EnforceMode mode, const EnforcePasses& passes,
                    const EnforcedRowFn& out, EnforceStats& stats) {
    if (areas.size() != n) throw InputError(fmt::format("--enforce: {} areas for {} rows", areas.size(), n));
    for (std::uint32_t i = 0; i < n; ++i)
        if (!(areas[i] > 0)) throw InputError(fmt::format("--enforce: patch {} has area {} (must be > 0)", i, areas[i]));
    const bool closure = mode == EnforceMode::Closure;
    std::vector<double> d(n, 1.0);
    FigureSums before, after;
    std::vector<std::uint32_t> gcol;
    std::vector<double> gval, oval, mirror;
    // The enforced row i from row i of G: d_i G_ij d_j / A_i, and its mirror d_j G_ji d_i / A_j
    // with G_ji == G_ij.
    const GRowFn emit = [&](std::uint32_t i, std::span<const std::uint32_t> col, std::span<const double> val) {
        oval.resize(col.size());
        mirror.resize(col.size());
        double s = 0;
        for (std::size_t k = 0; k < col.size(); ++k) {
            const std::uint32_t j = col[k];
            oval[k] = d[i] * val[k] * d[j] / areas[i];
            mirror[k] = d[j] * val[k] * d[i] / areas[j];
            s += oval[k];
        }
        after.row_sum(s);
        for (std::size_t k = 0; k < col.size(); ++k) after.pair(areas[i], oval[k], areas[col[k]], mirror[k]);
        out(i, col, oval, mirror);
    };

    // G = (A F + (A F)ᵀ) / 2 on the union pattern: row i of F merged with column i by j; a
    // missing entry is 0. Each present entry adds its half (the sum of two halves does not depend
    // on their order).
    std::uint32_t next = 0;
    passes.rows_and_columns([&](std::uint32_t i, RowView row, RowView column) {
        FFCUBE_CHECK(i == next && i < n);
        ++next;
        before.row_sum(row.sum());
        gcol.clear();
        gval.clear();
        std::size_t x = 0, y = 0;
        while (x < row.col.size() || y < column.col.size()) {
            const std::uint32_t jr = x < row.col.size() ? row.col[x] : ~0u;
            const std::uint32_t jc = y < column.col.size() ? column.col[y] : ~0u;
            const std::uint32_t j = std::min(jr, jc);
            double g = 0;
            const double fij = jr == j ? static_cast<double>(row.val[x++]) : 0.0;
            const double fji = jc == j ? static_cast<double>(column.val[y++]) : 0.0;
            if (jr == j) g += areas[i] * fij / 2;
            if (jc == j) g += areas[j] * fji / 2;
            if (jr == j) before.pair(areas[i], fij, areas[j], fji);
            gcol.push_back(j);
            gval.push_back(g);
        }
        if (!closure) {
            emit(i, gcol, gval);
            return;
        }
        if (gcol.empty())
            throw InputError(fmt::format("--enforce closure: patch {} neither sees nor is seen by any patch", i));
        passes.store_g(i, gcol, gval);
    });
    FFCUBE_CHECK_MSG(next == n, "a pass over the matrix missed rows");
    stats.before = before.figures();

    if (closure) {
        // Symmetric scaling d_i Σ_j G_ij d_j = A_i, one pass over G per iteration.
        std::vector<double> gd(n);
        constexpr unsigned kMaxIterations = 100000;
        constexpr double kTarget = 1e-12;  // max |row sum − 1|
        unsigned it = 0;
        for (;; ++it) {
            double worst = 0;
            passes.stored_g([&](std::uint32_t i, std::span<const std::uint32_t> col, std::span<const double> val) {
                double s = 0;
                for (std::size_t k = 0; k < col.size(); ++k) s += val[k] * d[col[k]];
                gd[i] = s;
                worst = std::max(worst, std::abs(d[i] * s / areas[i] - 1.0));
            });
            if (passes.iteration) passes.iteration(it, worst, kTarget);
            if (worst <= kTarget) break;
            if (it == kMaxIterations)
                throw InputError(fmt::format(
                    "--enforce closure: no symmetric scaling reaches row sums of 1 (still {:.3g} off after {} iterations)",
                    worst, it));
            // Jacobi-style update from the sums of the previous iterate: deterministic and symmetric.
            for (std::uint32_t i = 0; i < n; ++i) d[i] = std::sqrt(d[i] * areas[i] / gd[i]);
        }
        stats.iterations = it;
        passes.stored_g(emit);
    }
    stats.after = after.figures();
}

EnforcedMatrix enforce(const CsrMatrix& F, std::span<const double> areas, EnforceMode mode, EnforceStats& stats,
                       const std::function<void(unsigned, double, double)>& iteration, Progress* rows) {
    const std::uint32_t n = F.size();
    FFCUBE_CHECK(F.rows_filled() == n);
    // Fᵀ: rows are read with i increasing, so each column lists its rows in increasing order.
    std::vector<std::uint64_t> tptr(std::size_t(n) + 1, 0);
    for (const std::uint32_t j : F.col()) ++tptr[j + 1];
    for (std::uint32_t j = 0; j < n; ++j) tptr[j + 1] += tptr[j];
    std::vector<std::uint32_t> trow(F.nnz());
    std::vector<float> tval(F.nnz());
    {
        std::vector<std::uint64_t> fill(tptr.begin(), tptr.end() - 1);
        for (std::uint32_t i = 0; i < n; ++i) {
            const RowView r = F.row(i);
            for (std::size_t k = 0; k < r.col.size(); ++k) {
                const std::uint64_t at = fill[r.col[k]]++;
                trow[at] = i;
                tval[at] = r.val[k];
            }
        }
    }
    EnforcedMatrix G, out;
    G.n = out.n = n;
    const auto append = [](EnforcedMatrix& m, std::span<const std::uint32_t> col, std::span<const double> val) {
        m.col.insert(m.col.end(), col.begin(), col.end());
        m.val.insert(m.val.end(), val.begin(), val.end());
        m.row_ptr.push_back(m.col.size());
    };
    EnforcePasses passes;
    passes.iteration = iteration;
    passes.rows_and_columns = [&](const RowColumnFn& f) {
        for (std::uint32_t i = 0; i < n; ++i) {
            const std::size_t b = tptr[i], e = tptr[i + 1];
            f(i, F.row(i), RowView{std::span(trow).subspan(b, e - b), std::span(tval).subspan(b, e - b)});
            if (rows) rows->add();
        }
        if (rows) rows->finish();
    };
    passes.store_g = [&](std::uint32_t, std::span<const std::uint32_t> col, std::span<const double> val) {
        append(G, col, val);
    };
    passes.stored_g = [&](const GRowFn& f) {
        for (std::uint32_t i = 0; i < n; ++i) {
            const std::size_t b = G.row_ptr[i], e = G.row_ptr[i + 1];
            f(i, std::span(G.col).subspan(b, e - b), std::span(G.val).subspan(b, e - b));
        }
    };
    enforce_passes(n, areas, mode, passes,
                   [&](std::uint32_t, std::span<const std::uint32_t> col, std::span<const double> val,
                       std::span<const double>) { append(out, col, val); },
                   stats);
    return out;
}

}  // namespace ffcube
