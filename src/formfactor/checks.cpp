#include "ffcube/formfactor/checks.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

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
      col_counts_(scene.size(), 0) {
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

std::vector<std::uint32_t> reciprocity_bands(std::span<const std::uint32_t> row_counts,
                                             std::span<const std::uint32_t> col_counts, std::uint64_t budget_entries) {
    FFCUBE_CHECK(row_counts.size() == col_counts.size());
    const auto n = static_cast<std::uint32_t>(row_counts.size());
    std::vector<std::uint32_t> starts{0};
    std::uint64_t held = 0;
    for (std::uint32_t i = 0; i < n; ++i) {
        const std::uint64_t e = std::uint64_t(row_counts[i]) + col_counts[i];
        if (held > 0 && held + e > budget_entries) {
            starts.push_back(i);
            held = 0;
        }
        held += e;
    }
    if (n > 0) starts.push_back(n);
    return starts;
}

double patch_reciprocity_banded(std::span<const double> areas, std::span<const std::uint32_t> row_counts,
                                std::span<const std::uint32_t> col_counts, const RowPass& pass,
                                std::uint64_t budget_entries, Progress* progress) {
    const std::vector<std::uint32_t> bands = reciprocity_bands(row_counts, col_counts, budget_entries);
    FFCUBE_CHECK(areas.size() == row_counts.size());
    double worst = 0.0;
    std::vector<std::uint64_t> rptr, cptr, rfill, cfill;
    std::vector<std::uint32_t> rcol, crow;
    std::vector<float> rval, cval;
    for (std::size_t b = 0; b + 1 < bands.size(); ++b) {
        const std::uint32_t lo = bands[b], hi = bands[b + 1], m = hi - lo;
        rptr.assign(std::size_t(m) + 1, 0);
        cptr.assign(std::size_t(m) + 1, 0);
        for (std::uint32_t k = 0; k < m; ++k) {
            rptr[k + 1] = rptr[k] + row_counts[lo + k];
            cptr[k + 1] = cptr[k] + col_counts[lo + k];
        }
        rcol.resize(rptr[m]);
        rval.resize(rptr[m]);
        crow.resize(cptr[m]);
        cval.resize(cptr[m]);
        rfill.assign(rptr.begin(), rptr.end() - 1);
        cfill.assign(cptr.begin(), cptr.end() - 1);
        pass([&](std::uint32_t j, RowView r) {
            if (progress) progress->add();
            if (j >= lo && j < hi) {
                FFCUBE_CHECK_MSG(r.col.size() == row_counts[j], "a pass over the matrix saw another row");
                std::copy(r.col.begin(), r.col.end(), rcol.begin() + static_cast<long>(rptr[j - lo]));
                std::copy(r.val.begin(), r.val.end(), rval.begin() + static_cast<long>(rptr[j - lo]));
            }
            // Rows come with j increasing, so each column's list is sorted by j.
            for (auto it = std::lower_bound(r.col.begin(), r.col.end(), lo); it != r.col.end() && *it < hi; ++it) {
                const std::uint32_t i = *it - lo;
                FFCUBE_CHECK_MSG(cfill[i] < cptr[i + 1], "a pass over the matrix saw another column");
                crow[cfill[i]] = j;
                cval[cfill[i]++] = r.val[static_cast<std::size_t>(it - r.col.begin())];
            }
        });
        for (std::uint32_t k = 0; k < m; ++k) {
            FFCUBE_CHECK_MSG(cfill[k] == cptr[k + 1], "a pass over the matrix saw another column");
            const std::uint32_t i = lo + k;
            const double ai = areas[i];
            std::uint64_t x = rptr[k], y = cptr[k];
            // Merge row i (F_ij) with column i (F_ji) by j; a missing entry is 0.
            while (x < rptr[k + 1] || y < cptr[k + 1]) {
                const std::uint32_t jr = x < rptr[k + 1] ? rcol[x] : ~0u, jc = y < cptr[k + 1] ? crow[y] : ~0u;
                const std::uint32_t j = std::min(jr, jc);
                const double fij = jr == j ? static_cast<double>(rval[x++]) : 0.0;
                const double fji = jc == j ? static_cast<double>(cval[y++]) : 0.0;
                const double aj = areas[j];
                // The expression of reciprocity_stats, so that both give the same number.
                worst = std::max(worst, std::abs(ai * fij - aj * fji) / (0.5 * (ai + aj)));
            }
        }
    }
    return worst;
}

}  // namespace ffcube
