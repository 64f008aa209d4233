// Consistency checks on a form-factor matrix: row sums and reciprocity (A_i F_ij = A_j F_ji),
// per patch and per object. Pure CPU; used by reports, tests and the bench.
#pragma once

#include <cstdint>
#include <functional>
#include <span>
#include <string>
#include <vector>

#include "ffcube/core/progress.hpp"
#include "ffcube/formfactor/sparse.hpp"
#include "ffcube/scene/scene.hpp"

namespace ffcube {

struct RowSumStats {
    double min = 0.0, max = 0.0, mean = 0.0;
};
RowSumStats row_sum_stats(const CsrMatrix& F);

// Object-to-object form factors: G[a][b] = Σ_{i∈a} A_i Σ_{j∈b} F_ij / Σ_{i∈a} A_i (dense, objects²).
std::vector<std::vector<double>> object_form_factors(const CsrMatrix& F, const Scene& scene);

struct ReciprocityStats {
    // max over patch pairs of |A_i F_ij − A_j F_ji| / (A_i + A_j)·2: an absolute deviation in units of F
    // for equal-area patches.
    double patch_max_abs = 0.0;
    // max over object pairs of |A_a G_ab − A_b G_ba| / max(A_a G_ab, A_b G_ba) (pairs with G > 0).
    double object_max_rel = 0.0;
};
// progress, when given, is advanced by one per row of F (at 100k patches and 1.6e9 non-zeros
// the pass takes minutes: its reads of F_ji are scattered over the whole matrix).
ReciprocityStats reciprocity_stats(const CsrMatrix& F, const Scene& scene, Progress* progress = nullptr);

// The same figures from rows fed one at a time in order (a matrix streamed to a file), in
// memory independent of the number of entries: O(objects²) for the object factors and O(n) for
// the entry counts per row and per column (which io/transpose_scratch.hpp plans with). The
// in-memory functions above are this class fed every row of F, so both give identical numbers.
class RowStreamChecks {
public:
    explicit RowStreamChecks(const Scene& scene);
    void add(std::uint32_t i, RowView row);  // rows 0, 1, ... in order
    RowSumStats row_sums() const;
    std::vector<std::vector<double>> object_factors() const;  // as object_form_factors
    double object_max_rel() const;                            // as ReciprocityStats::object_max_rel
    const std::vector<std::uint32_t>& row_counts() const { return row_counts_; }
    const std::vector<std::uint32_t>& col_counts() const { return col_counts_; }
    // Per column c, its entries below the diagonal (rows i > c): ColumnPart::below_diagonal's counts.
    const std::vector<std::uint32_t>& lower_col_counts() const { return lower_col_counts_; }
    // Entries right of the diagonal (F_ij, j > i): the rows ColumnPart::below_diagonal gives.
    std::uint64_t upper_entries() const { return upper_entries_; }

private:
    const Scene& scene_;
    std::uint32_t rows_ = 0;
    double min_ = 0, max_ = 0, total_ = 0;
    std::vector<std::vector<double>> g_;  // Σ A_i F_ij per object pair, not yet divided
    std::vector<double> area_;            // per object, of the rows seen
    std::vector<std::uint32_t> row_counts_, col_counts_, lower_col_counts_;
    std::uint64_t upper_entries_ = 0;
};

// One pass over a matrix: calls its argument with every row, in order (e.g. FfmReader::for_each_row).
using RowPass = std::function<void(const std::function<void(std::uint32_t, RowView)>&)>;
// Row i of a matrix with its column i (row i of the transpose: row indices increasing and the
// values F_ki), as io/transpose_scratch.hpp's for_each_row_and_column gives them.
using RowAndColumnFn = std::function<void(std::uint32_t i, RowView row, RowView column)>;
// Which part of column i for_each_row_and_column (io/transpose_scratch.hpp) gives: every F_ki,
// or only those below the diagonal (k > i), half the entries to hold and spill, which is all a
// check symmetric in the pair needs (PatchReciprocity).
enum class ColumnPart { all, below_diagonal };

// ReciprocityStats::patch_max_abs (the same number as reciprocity_stats gives for the matrix in
// memory) from every row i with its column i, fed in any order: row and column merged by j, a
// missing entry 0. areas must outlive it. Fed ColumnPart::below_diagonal's halves (row i right
// of the diagonal, column i below it), each pair is looked at once, from the row of its lower
// index: the measure is symmetric in the pair bit for bit (|a − b| = |b − a|, A_i + A_j =
// A_j + A_i), so the maximum is the same number.
class PatchReciprocity {
public:
    explicit PatchReciprocity(std::span<const double> areas) : areas_(areas) {}
    void add(std::uint32_t i, RowView row, RowView column);
    double max_abs() const { return worst_; }

private:
    std::span<const double> areas_;
    double worst_ = 0.0;
};

// PatchReciprocity while the rows stream (rows 0, 1, ... in order, as they are written): row j's
// entries left of the diagonal are paired with column j's entries above it, F_kj for k < j,
// which the rows before j left here; entries right of the diagonal wait for their column's row,
// and a column is let go once its row has come. Each pair is looked at once, from its higher
// index (the measure is symmetric bit for bit: the same maximum as the pass over the file). It
// holds the waiting entries (8 bytes each, up to twice that with the vectors' slack): at most
// max_entries of them, beyond which, or when a row comes out of order, it gives up and frees
// them (complete() false: the caller reads the file instead).
class StreamedPatchReciprocity {
public:
    StreamedPatchReciprocity(std::span<const double> areas, std::uint64_t max_entries);
    void add(std::uint32_t i, RowView row);
    // Every row 0 .. n − 1 came, in order, within the budget: max_abs() is the matrix's.
    bool complete() const { return !failed_ && next_ == areas_.size(); }
    double max_abs() const { return check_.max_abs(); }
    std::uint64_t peak_entries() const { return peak_; }

private:
    void give_up();
    std::span<const double> areas_;
    std::uint64_t max_entries_;
    PatchReciprocity check_;
    std::vector<std::vector<std::uint32_t>> rows_;  // per column j: the rows k < j with F_kj > 0 so far
    std::vector<std::vector<float>> vals_;          // ... and their F_kj
    // A small scene (the whole lower triangle, 4 bytes an entry, within the budget): F_kj, k < j,
    // at dense_[j (j − 1) / 2 + k], zero where absent, instead of the lists: no list to grow.
    std::vector<float> dense_;
    std::vector<std::uint32_t> dense_col_;  // add()'s scratch: column i's rows with F_ki ≠ 0 ...
    std::vector<float> col_vals_;           // ... and those F_ki
    std::uint64_t held_ = 0, peak_ = 0;
    std::uint32_t next_ = 0;
    bool failed_ = false;
};

}  // namespace ffcube
