#include "ffcube/formfactor/row_provider.hpp"

#include <numeric>

#include "ffcube/core/error.hpp"

namespace ffcube {

void RowProvider::compute_row(std::uint32_t i, SparseRow& out) {
    const std::uint32_t rows[1] = {i};
    compute_rows(rows, [&](std::uint32_t, const SparseRow& r) { out = r; });
}

void RowProvider::compute_rows_planned(std::span<const std::uint32_t> rows, std::span<const RowPlan> plans,
                                       const RowSink& sink) {
    FFCUBE_CHECK_MSG(plans.size() == rows.size(), "compute_rows_planned: one plan per row");
    compute_rows(rows, sink);
}

void MatrixRowProvider::compute_rows(std::span<const std::uint32_t> rows, const RowSink& sink) {
    SparseRow tmp;
    for (std::uint32_t i : rows) {
        const RowView v = m_.row(i);
        tmp.col.assign(v.col.begin(), v.col.end());
        tmp.val.assign(v.val.begin(), v.val.end());
        sink(i, tmp);
    }
}

CsrMatrix compute_all_rows(RowProvider& provider) {
    const std::uint32_t n = provider.size();
    std::vector<std::uint32_t> all(n);
    std::iota(all.begin(), all.end(), 0u);
    CsrMatrix m(n);
    provider.compute_rows(all, [&](std::uint32_t i, const SparseRow& r) {
        FFCUBE_CHECK(i == m.rows_filled());
        m.append_row(r);
    });
    return m;
}

}  // namespace ffcube
