#include "ffcube/formfactor/checks.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>
#if defined(__GLIBC__)  // after a libc header has defined it
#include <malloc.h>
#endif

#include "ffcube/core/error.hpp"

namespace ffcube {
namespace {

// min, max and mean of row sums, accumulated in row order.
struct RowSums {
    double min = std::numeric_limits<double>::infinity(), max = -std::numeric_limits<double>::infinity(), total = 0;
    std::uint32_t rows = 0;
    void add(double r) {
        min = std::min(min, r);
        max = std::max(max, r);
        total += r;
        ++rows;
    }
    RowSumStats stats() const {
        if (rows == 0) return {};
        return {min, max, total / rows};
    }
};

}  // namespace

RowSumStats row_sum_stats(const CsrMatrix& F) {
    RowSums s;
    for (std::uint32_t i = 0; i < F.rows_filled(); ++i) s.add(F.row(i).sum());
    return s.stats();
}

RowStreamChecks::RowStreamChecks(const Scene& scene)
    : scene_(scene),
      g_(scene.objects.size(), std::vector<double>(scene.objects.size(), 0.0)),
      area_(scene.objects.size(), 0.0),
      col_counts_(scene.size(), 0),
      lower_col_counts_(scene.size(), 0) {
    row_counts_.reserve(scene.size());
}

void RowStreamChecks::add(std::uint32_t i, RowView r) {
    FFCUBE_CHECK(i == rows_ && i < scene_.size());
    ++rows_;
    const double s = r.sum();
    if (i == 0) min_ = max_ = s;
    min_ = std::min(min_, s);
    max_ = std::max(max_, s);
    total_ += s;
    const Patch& p = scene_.patches[i];
    area_[p.object] += p.area;
    std::vector<double>& g = g_[p.object];
    for (std::size_t k = 0; k < r.col.size(); ++k) {
        g[scene_.patches[r.col[k]].object] += p.area * static_cast<double>(r.val[k]);
        ++col_counts_[r.col[k]];
        lower_col_counts_[r.col[k]] += r.col[k] < i;
        upper_entries_ += r.col[k] > i;
    }
    row_counts_.push_back(static_cast<std::uint32_t>(r.col.size()));
}

RowSumStats RowStreamChecks::row_sums() const {
    if (rows_ == 0) return {};
    return {min_, max_, total_ / rows_};
}

std::vector<std::vector<double>> RowStreamChecks::object_factors() const {
    std::vector<std::vector<double>> G = g_;
    for (std::size_t a = 0; a < G.size(); ++a)
        if (area_[a] > 0)
            for (double& g : G[a]) g /= area_[a];
    return G;
}

double RowStreamChecks::object_max_rel() const {
    const auto G = object_factors();
    std::vector<double> area(scene_.objects.size(), 0.0);
    for (const Patch& p : scene_.patches) area[p.object] += p.area;
    double worst = 0.0;
    for (std::size_t a = 0; a < G.size(); ++a)
        for (std::size_t b = a + 1; b < G.size(); ++b) {
            const double x = area[a] * G[a][b], y = area[b] * G[b][a];
            const double mx = std::max(x, y);
            if (mx > 0) worst = std::max(worst, std::abs(x - y) / mx);
        }
    return worst;
}

std::vector<std::vector<double>> object_form_factors(const CsrMatrix& F, const Scene& scene) {
    FFCUBE_CHECK(F.size() == scene.size());
    RowStreamChecks c(scene);
    for (std::uint32_t i = 0; i < F.rows_filled(); ++i) c.add(i, F.row(i));
    return c.object_factors();
}

ReciprocityStats reciprocity_stats(const CsrMatrix& F, const Scene& scene, Progress* progress) {
    ReciprocityStats s;
    const std::uint32_t n = F.rows_filled();
    if (n != F.size()) return s;  // needs every row
    // F_ji for every entry F_ij: rows are visited with i increasing, so the entries (j, i) looked
    // up in a row j come in increasing column order too, and a cursor per row finds each in
    // amortised O(1) (O(nnz) in all; a binary search per entry was a quarter of a 3,744-patch run).
    // Every pair with F_ij > 0 is checked from row i, one with only F_ji > 0 from row j.
    std::vector<std::size_t> cursor(n, 0);
    RowStreamChecks objects(scene);
    for (std::uint32_t i = 0; i < n; ++i) {
        const RowView r = F.row(i);
        objects.add(i, r);
        const double ai = scene.patches[i].area;
        for (std::size_t k = 0; k < r.col.size(); ++k) {
            const std::uint32_t j = r.col[k];
            const RowView rj = F.row(j);
            std::size_t& c = cursor[j];
            while (c < rj.col.size() && rj.col[c] < i) ++c;
            const double fji = c < rj.col.size() && rj.col[c] == i ? static_cast<double>(rj.val[c]) : 0.0;
            const double aj = scene.patches[j].area;
            s.patch_max_abs = std::max(s.patch_max_abs, std::abs(ai * r.val[k] - aj * fji) / (0.5 * (ai + aj)));
        }
        if (progress) progress->add();
    }
    s.object_max_rel = objects.object_max_rel();
    return s;
}

void PatchReciprocity::add(std::uint32_t i, RowView row, RowView column) {
    FFCUBE_CHECK(i < areas_.size());
    const double ai = areas_[i];
    std::size_t x = 0, y = 0;
    while (x < row.col.size() || y < column.col.size()) {
        const std::uint32_t jr = x < row.col.size() ? row.col[x] : ~0u, jc = y < column.col.size() ? column.col[y] : ~0u;
        const std::uint32_t j = std::min(jr, jc);
        const double fij = jr == j ? static_cast<double>(row.val[x++]) : 0.0;
        const double fji = jc == j ? static_cast<double>(column.val[y++]) : 0.0;
        const double aj = areas_[j];
        // The expression of reciprocity_stats, so that both give the same number (a pair with
        // only F_ji > 0, checked there from row j, gives the same |difference| here).
        worst_ = std::max(worst_, std::abs(ai * fij - aj * fji) / (0.5 * (ai + aj)));
    }
}

namespace {

// Where column j's entries F_kj, k < j, start in the dense lower triangle (j (j − 1) / 2).
std::size_t column_start(std::uint32_t j) { return j == 0 ? 0 : static_cast<std::size_t>(j) * (j - 1) / 2; }

}  // namespace

StreamedPatchReciprocity::StreamedPatchReciprocity(std::span<const double> areas, std::uint64_t max_entries)
    : areas_(areas), max_entries_(max_entries), check_(areas) {
    const std::uint64_t n = areas.size();
    // The lists cost 16 bytes an entry held (max_entries_ of them); the dense triangle 4 bytes
    // for every pair: taken when it fits the same bytes.
    if (n >= 2 && n * (n - 1) / 2 * 4 <= max_entries_ * 16) {
        dense_.assign(n * (n - 1) / 2, 0.0f);
    } else {
        rows_.resize(n);
        vals_.resize(n);
    }
}

void StreamedPatchReciprocity::give_up() {
    failed_ = true;
    std::vector<std::vector<std::uint32_t>>().swap(rows_);
    std::vector<std::vector<float>>().swap(vals_);
    std::vector<float>().swap(dense_);
    held_ = 0;
#if defined(__GLIBC__)
    // The lists were many small blocks: hand the freed heap back, so that the passes over the
    // file that follow start from the memory the run had before (the 1 GB bound at 100k patches).
    malloc_trim(0);
#endif
}

void StreamedPatchReciprocity::add(std::uint32_t i, RowView row) {
    if (failed_) return;
    if (i != next_ || i >= areas_.size()) {
        give_up();
        return;
    }
    ++next_;
    // Row i left of the diagonal with column i above it (every row k < i has come).
    const auto left = static_cast<std::size_t>(std::lower_bound(row.col.begin(), row.col.end(), i) - row.col.begin());
    if (!dense_.empty()) {
        // Column i's nonzero entries (F_ki > 0 is what the lists hold), then row i's right part
        // into the triangle.
        const float* const column = dense_.data() + column_start(i);
        dense_col_.clear();
        col_vals_.clear();
        for (std::uint32_t k = 0; k < i; ++k)
            if (column[k] != 0.0f) {
                dense_col_.push_back(k);
                col_vals_.push_back(column[k]);
            }
        check_.add(i, RowView{row.col.first(left), row.val.first(left)}, RowView{dense_col_, col_vals_});
        held_ -= dense_col_.size();
        for (std::size_t x = left; x < row.col.size(); ++x) {
            const std::uint32_t j = row.col[x];
            if (j == i) continue;
            dense_[column_start(j) + i] = row.val[x];
            held_ += row.val[x] != 0.0f;
        }
        peak_ = std::max(peak_, held_);
        return;
    }
    check_.add(i, RowView{row.col.first(left), row.val.first(left)}, RowView{rows_[i], vals_[i]});
    held_ -= rows_[i].size();
    std::vector<std::uint32_t>().swap(rows_[i]);
    std::vector<float>().swap(vals_[i]);
    // Right of the diagonal (past i itself): each entry waits in its column for that column's row.
    for (std::size_t x = left; x < row.col.size(); ++x) {
        const std::uint32_t j = row.col[x];
        if (j == i) continue;
        rows_[j].push_back(i);
        vals_[j].push_back(row.val[x]);
        ++held_;
    }
    peak_ = std::max(peak_, held_);
    if (held_ > max_entries_) give_up();
}

}  // namespace ffcube
