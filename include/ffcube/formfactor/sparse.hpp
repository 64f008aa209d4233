// Sparse rows of the form-factor matrix and the CSR matrix that holds them.
// Convention everywhere in ffcube: F[i][j] = fraction of the energy leaving patch i (diffusely,
// from its front) that arrives at patch j's front. Row i sums to the fraction of i's energy that
// lands on any front face (1 in a closed enclosure). F[i][i] = 0 for planar patches.
#pragma once

#include <cmath>
#include <cstdint>
#include <span>
#include <vector>

namespace ffcube {

// What a row carries besides its entries, from the provider that made it to every sink (a
// checkpoint's record, an MPI rank's chunk, the report's per-row figures, the sky and the patch
// table): nothing travels beside the rows in arrays of their own.
struct RowSide {
    // The share of the energy leaving the patch that obstruction-only surfaces intercept
    // (Scene::drawn: left out of F, and not sky); 0 without them.
    double obstructed = 0.0;
    // The near-field correction's estimates (docs/accuracy.md): Σ_j |F_ij − exact_ij|, and the
    // estimate the tolerance is held to (of the larger of the largest entry's and the sum's
    // error). NaN: the row has none (no correction, or a row read from a file that keeps none).
    float error = NAN;
    float tolerance_error = NAN;
    // How the row was measured (CorrectedRowProvider::RowMeasure); −1: not recorded.
    std::int8_t measure = -1;

    bool operator==(const RowSide& o) const {
        const auto same = [](float a, float b) { return (std::isnan(a) && std::isnan(b)) || a == b; };
        return obstructed == o.obstructed && same(error, o.error) && same(tolerance_error, o.tolerance_error) &&
               measure == o.measure;
    }
};

// One row: column indices strictly increasing, values > 0, and its side figures.
struct SparseRow {
    std::vector<std::uint32_t> col;
    std::vector<double> val;
    RowSide side;

    void clear() {
        col.clear();
        val.clear();
        side = RowSide{};
    }
    std::size_t nnz() const { return col.size(); }
    double sum() const;
    // The sum of the row as a CsrMatrix stores it: each entry rounded to float, summed in double
    // in column order; equal bit for bit to RowView::sum of the appended row (the same rule).
    double stored_sum() const;
};

// Read-only view of one row of a CsrMatrix (whose rows keep no side figures), or of a row as it
// comes from a feed (a checkpoint's record, an MPI chunk: pipeline/form_factors.hpp), with them.
struct RowView {
    std::span<const std::uint32_t> col;
    std::span<const float> val;
    RowSide side{};
    double sum() const;
};

// Compressed sparse rows, n × n, values stored as float (F entries are fractions in [0,1]; float's
// 6e-8 relative error is far below the hemicube's discretisation error). Sums are taken in double.
class CsrMatrix {
public:
    CsrMatrix() = default;
    explicit CsrMatrix(std::uint32_t n);

    std::uint32_t size() const { return n_; }
    std::uint64_t nnz() const { return col_.size(); }
    // Rows must be appended in order 0, 1, ..., n-1.
    void append_row(const SparseRow& row);
    void append_row(std::span<const std::uint32_t> col, std::span<const float> val);
    std::uint32_t rows_filled() const { return static_cast<std::uint32_t>(row_ptr_.size() - 1); }
    RowView row(std::uint32_t i) const;
    double at(std::uint32_t i, std::uint32_t j) const;  // binary search; 0 when absent

    const std::vector<std::uint64_t>& row_ptr() const { return row_ptr_; }
    const std::vector<std::uint32_t>& col() const { return col_; }
    const std::vector<float>& val() const { return val_; }
    // For readers that fill the arrays directly (validated by the caller).
    static CsrMatrix from_arrays(std::uint32_t n, std::vector<std::uint64_t> row_ptr, std::vector<std::uint32_t> col,
                                 std::vector<float> val);

private:
    std::uint32_t n_ = 0;
    std::vector<std::uint64_t> row_ptr_{0};
    std::vector<std::uint32_t> col_;
    std::vector<float> val_;
};

}  // namespace ffcube
