// Sparse rows of the form-factor matrix and the CSR matrix that holds them.
// Convention everywhere in ffcube: F[i][j] = fraction of the energy leaving patch i (diffusely,
// from its front) that arrives at patch j's front. Row i sums to the fraction of i's energy that
// lands on any front face (1 in a closed enclosure). F[i][i] = 0 for planar patches.
#pragma once

#include <cstdint>
#include <span>
#include <vector>

namespace ffcube {

// One row: column indices strictly increasing, values > 0.
struct SparseRow {
    std::vector<std::uint32_t> col;
    std::vector<double> val;

    void clear() {
        col.clear();
        val.clear();
    }
    std::size_t nnz() const { return col.size(); }
    double sum() const;
    // The sum of the row as a CsrMatrix stores it: each entry rounded to float, summed in double
    // in column order; equal bit for bit to RowView::sum of the appended row (the same rule).
    double stored_sum() const;
};

// Read-only view of one row of a CsrMatrix.
struct RowView {
    std::span<const std::uint32_t> col;
    std::span<const float> val;
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
