// Reciprocity and closure enforcement on a finished form-factor matrix (`--enforce`).
//
//  * reciprocity: G_ij = (A_i F_ij + A_j F_ji) / 2 on the union of the two patterns, then
//    F_ij = G_ij / A_i. Row sums change by the antisymmetric part only.
//  * closure (implies reciprocity): symmetric diagonal scaling of G, d_i Σ_j G_ij d_j = A_i,
//    by the symmetric Sinkhorn–Knopp iteration d_i ← √(d_i A_i / (G d)_i) until every row sums to
//    1 within 1e-12; F_ij = d_i G_ij d_j / A_i. G stays symmetric, so reciprocity is kept.
// Both only rescale non-negative numbers: no entry becomes negative.
// Closure is only meaningful for closed scenes: in an open one, rows sum below 1 because light
// escapes, and scaling them up would hide that. require_closed() refuses such matrices.
// Results are kept in double (EnforcedMatrix): CsrMatrix stores float, whose 6e-8 relative
// rounding would undo the 1e-12 closure; to_csr() makes the float matrix for writing.
#pragma once

#include <cstdint>
#include <functional>
#include <limits>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "ffcube/formfactor/checks.hpp"
#include "ffcube/formfactor/sparse.hpp"

namespace ffcube {

class Progress;

enum class EnforceMode { Reciprocity, Closure };

// Parses "reciprocity", "closure" or "both" (= closure, which implies reciprocity); InputError
// otherwise.
EnforceMode parse_enforce_mode(const std::string& name);

struct EnforcedMatrix {
    std::uint32_t n = 0;
    std::vector<std::uint64_t> row_ptr{0};
    std::vector<std::uint32_t> col;
    std::vector<double> val;
    double at(std::uint32_t i, std::uint32_t j) const;  // 0 when absent
    double row_sum(std::uint32_t i) const;
    CsrMatrix to_csr() const;
};

struct MatrixFigures {
    double row_sum_min = 0, row_sum_max = 0;
    // max over pairs of |A_i F_ij − A_j F_ji| / ((A_i + A_j)/2): absolute, in units of F.
    double reciprocity_max = 0;
};

struct EnforceStats {
    MatrixFigures before, after;
    unsigned iterations = 0;  // closure iterations (0 for reciprocity only)
};

// Throws InputError when some row sums below 1 − tolerance (row, its sum and the rule named):
// the scene is open (or a row missed part of its view) and closure would hide escaping light.
void require_closed(const CsrMatrix& F, double tolerance);

// The closure-refusal policy of `--enforce closure|both`, judged on the evidence of the provider
// that measured the rows (a correction may have rebalanced rows to 1, hiding an open scene):
//  * hemicube_miss_weight: Σ ΔF of hemicube pixels that saw nothing (NaN: not a hemicube). Any
//    positive value means light escapes.
//  * inner_row_sum_min: the smallest row sum before the near-field correction (NaN: no
//    correction). Below 1 − 1e-3 is open; ray-cast rows of a closed scene sum to 1 up to rays lost
//    at cracks, and 1e-3 tolerates few.
//  * otherwise F itself is judged by require_closed(F, 1e-3).
// Throws InputError naming `what` (the option as given) and the evidence.
struct ClosureEvidence {
    double hemicube_miss_weight = std::numeric_limits<double>::quiet_NaN();
    double inner_row_sum_min = std::numeric_limits<double>::quiet_NaN();
};
void require_closed_scene(std::string_view what, const ClosureEvidence& evidence, const CsrMatrix& F);
// The same judged on F's row sums (row_sums[i] = F.row(i).sum()), for a matrix streamed to a file.
void require_closed_scene(std::string_view what, const ClosureEvidence& evidence, std::span<const double> row_sums);

// areas.size() == F.size(), every area > 0 (InputError otherwise). Closure also throws
// InputError for a row with no entries (nothing to scale) and when 100000 iterations do not
// reach 1e-12 (the pattern has no symmetric scaling, e.g. a patch seen by no one).
// iteration, when given: as EnforcePasses::iteration. rows, when given: a step per row of the
// pass over rows and columns (the whole of reciprocity's work), finished after it.
EnforcedMatrix enforce(const CsrMatrix& F, std::span<const double> areas, EnforceMode mode, EnforceStats& stats,
                       const std::function<void(unsigned, double, double)>& iteration = {}, Progress* rows = nullptr);

MatrixFigures matrix_figures(const EnforcedMatrix& F, std::span<const double> areas);

// enforce() as passes over rows, for a matrix that is not held in memory (pipeline/
// streamed_enforce.hpp feeds it from a .ffm and scratch files). enforce() is this function fed
// from memory, so both give the same numbers to the last bit.
//  1. rows_and_columns: one pass over every row i of F together with its column i (row i of Fᵀ,
//     row indices increasing), in order. It gives the `before` figures and row i of G (the union
//     pattern; each value A_i F_ij / 2 + A_j F_ji / 2). Reciprocity: the enforced row i is then
//     made and handed to `out` at once. Closure: row i of G goes to store_g.
//  2. Closure only: each iteration is one stored_g pass (every row of G given to store_g, in
//     order), and a last one makes the enforced rows.
// out gets row i of the enforced matrix in double, and mirror[k] = the enforced F_{col[k], i}
// (G is exactly symmetric, so the transposed entry is computed locally, in enforce()'s
// expression). Memory: O(n) besides what the passes hold.
using RowColumnFn = RowAndColumnFn;
using GRowFn = std::function<void(std::uint32_t i, std::span<const std::uint32_t> col, std::span<const double> val)>;
using ClosureIterationFn = std::function<void(unsigned iteration, double worst, double target)>;
struct EnforcePasses {
    std::function<void(const RowColumnFn&)> rows_and_columns;
    GRowFn store_g;                               // closure only
    std::function<void(const GRowFn&)> stored_g;  // closure only
    // Closure, optional: after each scaling iteration's pass over G, the iteration (from 0), the
    // largest |row sum - 1| it measured and the target (1e-12): the caller's progress line.
    ClosureIterationFn iteration;
};
using EnforcedRowFn = std::function<void(std::uint32_t i, std::span<const std::uint32_t> col,
                                         std::span<const double> val, std::span<const double> mirror)>;
void enforce_passes(std::uint32_t n, std::span<const double> areas, EnforceMode mode, const EnforcePasses& passes,
                    const EnforcedRowFn& out, EnforceStats& stats);

}  // namespace ffcube
