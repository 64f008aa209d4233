// Rows carried from one adaptive level to the next (row_reuse.hpp).
#include "row_reuse.hpp"

#include <algorithm>
#include <limits>
#include <utility>

#include "ffcube/core/error.hpp"

namespace ffcube {
namespace {

constexpr std::uint32_t kNone = std::numeric_limits<std::uint32_t>::max();

// F_ci from row c (columns strictly increasing), 0 when absent.
double entry(const SparseRow& row, std::uint32_t column) {
    const auto it = std::lower_bound(row.col.begin(), row.col.end(), column);
    return it != row.col.end() && *it == column ? row.val[static_cast<std::size_t>(it - row.col.begin())] : 0.0;
}

}  // namespace

ReusedRowProvider::ReusedRowProvider(const Scene& scene, RowProvider& inner, std::span<const std::uint32_t> parent,
                                     std::span<const std::uint32_t> split, LevelRows previous)
    : scene_(scene), inner_(inner), parent_(parent.begin(), parent.end()), split_(split.begin(), split.end()),
      previous_(std::move(previous)) {
    const std::size_t n = scene.size();
    FFCUBE_CHECK_MSG(parent_.size() == n && inner.size() == n, "one parent per element");
    FFCUBE_CHECK_MSG(previous_.rows.empty() || (previous_.rows.size() == split_.size() && previous_.present.size() == split_.size()),
                     "the previous level's rows are one per patch of its scene");
    rows_.rows.resize(n);
    rows_.present.assign(n, false);
    const std::size_t m = split_.size();
    old_to_new_.assign(m, kNone);
    children_start_.assign(m + 1, 0);
    for (std::uint32_t e = 0; e < n; ++e) {
        FFCUBE_CHECK(parent_[e] < m);
        ++children_start_[parent_[e] + 1];
        if (split_[parent_[e]] <= 1) old_to_new_[parent_[e]] = e;
    }
    for (std::size_t j = 0; j < m; ++j) children_start_[j + 1] += children_start_[j];
    children_.resize(n);
    std::vector<std::uint32_t> next(children_start_.begin(), children_start_.end() - 1);
    for (std::uint32_t e = 0; e < n; ++e) children_[next[parent_[e]]++] = e;  // in element order
}

void ReusedRowProvider::measure_fresh() {
    fresh_done_ = true;
    std::vector<std::uint32_t> fresh;
    for (std::uint32_t e = 0; e < size(); ++e) {
        const std::uint32_t p = parent_[e];
        if (previous_.rows.empty() || split_[p] > 1 || !previous_.present[p]) fresh.push_back(e);
    }
    // One batch: the inner provider keeps all its workers busy.
    inner_.compute_rows(fresh, [&](std::uint32_t e, const SparseRow& row) {
        rows_.rows[e] = row;
        rows_.present[e] = true;
    });
    measured_ = fresh.size();
}

void ReusedRowProvider::reuse(std::uint32_t e) {
    const std::uint32_t p = parent_[e];
    const SparseRow& old = previous_.rows[p];
    std::vector<std::pair<std::uint32_t, double>> entries;
    entries.reserve(old.nnz() + 8);
    for (std::size_t k = 0; k < old.nnz(); ++k) {
        const std::uint32_t j = old.col[k];
        const double f = old.val[k];
        if (split_[j] <= 1) {
            entries.emplace_back(old_to_new_[j], f);
            continue;
        }
        // Share F_pj among j's elements by what their measured rows send back to e (reciprocity).
        double total = 0.0, area = 0.0;
        for (std::uint32_t s = children_start_[j]; s < children_start_[j + 1]; ++s) {
            const std::uint32_t c = children_[s];
            total += scene_.patches[c].area * entry(rows_.rows[c], e);
            area += scene_.patches[c].area;
        }
        for (std::uint32_t s = children_start_[j]; s < children_start_[j + 1]; ++s) {
            const std::uint32_t c = children_[s];
            const double w = total > 0.0 ? scene_.patches[c].area * entry(rows_.rows[c], e) / total : scene_.patches[c].area / area;
            if (w > 0.0) entries.emplace_back(c, f * w);
        }
    }
    std::sort(entries.begin(), entries.end());
    SparseRow& row = rows_.rows[e];
    row.clear();
    for (const auto& [c, v] : entries) {
        row.col.push_back(c);
        row.val.push_back(v);
    }
    rows_.present[e] = true;
    ++reused_;
}

void ReusedRowProvider::compute_rows(std::span<const std::uint32_t> rows, const RowSink& sink) {
    if (!fresh_done_) measure_fresh();
    for (const std::uint32_t e : rows) {
        FFCUBE_CHECK(e < size());
        if (!rows_.present[e]) reuse(e);
        sink(e, rows_.rows[e]);
    }
}

}  // namespace ffcube
