#include "ffcube/formfactor/checks.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "ffcube/core/error.hpp"

namespace ffcube {

RowSumStats row_sum_stats(const CsrMatrix& F) {
    RowSumStats s;
    const std::uint32_t n = F.rows_filled();
    if (n == 0) return s;
    s.min = std::numeric_limits<double>::infinity();
    s.max = -s.min;
    double total = 0.0;
    for (std::uint32_t i = 0; i < n; ++i) {
        const double r = F.row(i).sum();
        s.min = std::min(s.min, r);
        s.max = std::max(s.max, r);
        total += r;
    }
    s.mean = total / n;
    return s;
}

std::vector<std::vector<double>> object_form_factors(const CsrMatrix& F, const Scene& scene) {
    FFCUBE_CHECK(F.size() == scene.size());
    const std::size_t m = scene.objects.size();
    std::vector<std::vector<double>> G(m, std::vector<double>(m, 0.0));
    std::vector<double> area(m, 0.0);
    for (std::uint32_t i = 0; i < F.rows_filled(); ++i) {
        const Patch& p = scene.patches[i];
        area[p.object] += p.area;
        const RowView r = F.row(i);
        for (std::size_t k = 0; k < r.col.size(); ++k)
            G[p.object][scene.patches[r.col[k]].object] += p.area * static_cast<double>(r.val[k]);
    }
    for (std::size_t a = 0; a < m; ++a)
        if (area[a] > 0)
            for (double& g : G[a]) g /= area[a];
    return G;
}

ReciprocityStats reciprocity_stats(const CsrMatrix& F, const Scene& scene) {
    ReciprocityStats s;
    const std::uint32_t n = F.rows_filled();
    if (n != F.size()) return s;  // needs every row
    for (std::uint32_t i = 0; i < n; ++i) {
        const RowView r = F.row(i);
        const double ai = scene.patches[i].area;
        for (std::size_t k = 0; k < r.col.size(); ++k) {
            const std::uint32_t j = r.col[k];
            if (j < i) continue;  // each pair once (entries with j<i are seen from row j if F_ji>0)
            const double aj = scene.patches[j].area;
            const double d = std::abs(ai * r.val[k] - aj * F.at(j, i)) / (0.5 * (ai + aj));
            s.patch_max_abs = std::max(s.patch_max_abs, d);
        }
        // pairs where F_ij = 0 but F_ji > 0 are caught from row j's side with j < i? No: cover them here.
        for (std::size_t k = 0; k < r.col.size(); ++k) {
            const std::uint32_t j = r.col[k];
            if (j >= i) continue;
            if (F.at(j, i) == 0.0) {
                const double aj = scene.patches[j].area;
                s.patch_max_abs = std::max(s.patch_max_abs, ai * r.val[k] / (0.5 * (ai + aj)));
            }
        }
    }
    const auto G = object_form_factors(F, scene);
    std::vector<double> area(scene.objects.size(), 0.0);
    for (const Patch& p : scene.patches) area[p.object] += p.area;
    for (std::size_t a = 0; a < G.size(); ++a)
        for (std::size_t b = a + 1; b < G.size(); ++b) {
            const double x = area[a] * G[a][b], y = area[b] * G[b][a];
            const double mx = std::max(x, y);
            if (mx > 0) s.object_max_rel = std::max(s.object_max_rel, std::abs(x - y) / mx);
        }
    return s;
}

}  // namespace ffcube
