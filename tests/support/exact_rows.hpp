// The true error of a measured row of a scene without occluders, where every entry F_ij is the
// closed-form polygon factor ff_polygon_polygon (error ≲ 1e-12 relative): the larger of the
// row's largest entry error and its sum error, the quantity a tolerance estimate is of
// (docs/accuracy.md, "Accuracy by target").
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <vector>

#include "ffcube/formfactor/sparse.hpp"
#include "ffcube/geometry/analytic.hpp"
#include "ffcube/scene/scene.hpp"

namespace ffcube::test {

inline double unoccluded_row_error(const Scene& scene, std::uint32_t i, const SparseRow& row) {
    const std::uint32_t n = static_cast<std::uint32_t>(scene.size());
    const auto pi = scene.patch_vertices(i);
    std::vector<double> exact(n, 0.0), measured(n, 0.0);
    for (std::uint32_t j = 0; j < n; ++j)
        if (j != i) exact[j] = ff_polygon_polygon(pi, scene.patch_vertices(j));
    for (std::size_t a = 0; a < row.nnz(); ++a) measured[row.col[a]] = row.val[a];
    double entry = 0, sum_m = 0, sum_e = 0;
    for (std::uint32_t j = 0; j < n; ++j) {
        entry = std::max(entry, std::abs(measured[j] - exact[j]));
        sum_m += measured[j], sum_e += exact[j];
    }
    return std::max(entry, std::abs(sum_m - sum_e));
}

}  // namespace ffcube::test
