// Merging an inner row with analytic entries (see row_merge.hpp).
#include "accuracy/row_merge.hpp"

namespace ffcube::accuracy {

std::uint64_t merge_row(const SparseRow& inner, std::span<const std::pair<std::uint32_t, double>> exact,
                        const SenderQuadrature& quadrature, const RowErrorModel& error, MergedRow& out,
                        double& estimate, RowNoise* noise) {
    out.clear();
    out.row.col.reserve(inner.nnz() + exact.size());
    out.row.val.reserve(inner.nnz() + exact.size());
    out.is_exact.reserve(inner.nnz() + exact.size());
    std::uint64_t rescaled = 0;
    out.noise.resize(inner.nnz());
    error.noise(inner.val, out.noise.data());
    std::size_t a = 0, b = 0;
    while (a < inner.nnz() || b < exact.size()) {
        if (b == exact.size() || (a < inner.nnz() && inner.col[a] < exact[b].first)) {
            const SenderQuadrature::Entry e = quadrature.rescale(inner.col[a], inner.val[a]);
            rescaled += e.rescaled;
            estimate += e.systematic + out.noise[a];
            if (noise) noise->add(out.noise[a]);
            if (e.value > 0) {
                out.row.col.push_back(inner.col[a]);
                out.row.val.push_back(e.value);
                out.is_exact.push_back(0);
            }
            ++a;
            continue;
        }
        if (a < inner.nnz() && inner.col[a] == exact[b].first) {
            if (noise) noise->replaced_sum_sq += out.noise[a] * out.noise[a];
            ++a;
        }
        if (exact[b].second > 0) {
            out.row.col.push_back(exact[b].first);
            out.row.val.push_back(exact[b].second);
            out.is_exact.push_back(1);
        }
        ++b;
    }
    return rescaled;
}

}  // namespace ffcube::accuracy
