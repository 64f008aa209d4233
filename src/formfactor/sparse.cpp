#include "ffcube/formfactor/sparse.hpp"

#include <algorithm>

#include "ffcube/core/error.hpp"

namespace ffcube {

double SparseRow::sum() const {
    double s = 0.0;
    for (double v : val) s += v;
    return s;
}

namespace {

// The one rule of a stored row's sum (CsrMatrix keeps float entries): each entry as float, summed
// in double, in order. --sky's file bytes depend on SparseRow::stored_sum and RowView::sum agreeing.
template <typename T>
double float_entries_sum(std::span<const T> val) {
    double s = 0.0;
    for (const T v : val) s += static_cast<float>(v);
    return s;
}

}  // namespace

double SparseRow::stored_sum() const { return float_entries_sum<double>(val); }

double RowView::sum() const { return float_entries_sum<float>(val); }

CsrMatrix::CsrMatrix(std::uint32_t n) : n_(n) { row_ptr_.reserve(std::size_t(n) + 1); }

void CsrMatrix::append_row(const SparseRow& row) {
    FFCUBE_CHECK(row.col.size() == row.val.size());
    FFCUBE_CHECK(rows_filled() < n_);
    for (std::size_t k = 0; k < row.col.size(); ++k) {
        FFCUBE_CHECK(row.col[k] < n_ && (k == 0 || row.col[k] > row.col[k - 1]));
        col_.push_back(row.col[k]);
        val_.push_back(static_cast<float>(row.val[k]));
    }
    row_ptr_.push_back(col_.size());
}

void CsrMatrix::append_row(std::span<const std::uint32_t> col, std::span<const float> val) {
    FFCUBE_CHECK(col.size() == val.size());
    FFCUBE_CHECK(rows_filled() < n_);
    for (std::size_t k = 0; k < col.size(); ++k) FFCUBE_CHECK(col[k] < n_ && (k == 0 || col[k] > col[k - 1]));
    col_.insert(col_.end(), col.begin(), col.end());
    val_.insert(val_.end(), val.begin(), val.end());
    row_ptr_.push_back(col_.size());
}

RowView CsrMatrix::row(std::uint32_t i) const {
    FFCUBE_CHECK(i < rows_filled());
    const std::uint64_t b = row_ptr_[i], e = row_ptr_[i + 1];
    return RowView{std::span<const std::uint32_t>(col_.data() + b, e - b), std::span<const float>(val_.data() + b, e - b)};
}

double CsrMatrix::at(std::uint32_t i, std::uint32_t j) const {
    const RowView r = row(i);
    auto it = std::lower_bound(r.col.begin(), r.col.end(), j);
    if (it == r.col.end() || *it != j) return 0.0;
    return r.val[static_cast<std::size_t>(it - r.col.begin())];
}

CsrMatrix CsrMatrix::from_arrays(std::uint32_t n, std::vector<std::uint64_t> row_ptr, std::vector<std::uint32_t> col,
                                 std::vector<float> val) {
    FFCUBE_CHECK(row_ptr.size() == std::size_t(n) + 1 && row_ptr.front() == 0 && row_ptr.back() == col.size() &&
                 col.size() == val.size());
    CsrMatrix m;
    m.n_ = n;
    m.row_ptr_ = std::move(row_ptr);
    m.col_ = std::move(col);
    m.val_ = std::move(val);
    return m;
}

}  // namespace ffcube
