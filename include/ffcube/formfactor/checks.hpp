// Consistency checks on a form-factor matrix: row sums and reciprocity (A_i F_ij = A_j F_ji),
// per patch and per object. Pure CPU; used by reports, tests and the bench.
#pragma once

#include <string>
#include <vector>

#include "ffcube/core/progress.hpp"
#include "ffcube/formfactor/sparse.hpp"
#include "ffcube/scene/scene.hpp"

namespace ffcube {

struct RowSumStats {
    double min = 0.0, max = 0.0, mean = 0.0;
};
RowSumStats row_sum_stats(const CsrMatrix& F);

// Object-to-object form factors: G[a][b] = Σ_{i∈a} A_i Σ_{j∈b} F_ij / Σ_{i∈a} A_i (dense, objects²).
std::vector<std::vector<double>> object_form_factors(const CsrMatrix& F, const Scene& scene);

struct ReciprocityStats {
    // max over patch pairs of |A_i F_ij − A_j F_ji| / (A_i + A_j)·2: an absolute deviation in units of F
    // for equal-area patches.
    double patch_max_abs = 0.0;
    // max over object pairs of |A_a G_ab − A_b G_ba| / max(A_a G_ab, A_b G_ba) (pairs with G > 0).
    double object_max_rel = 0.0;
};
// progress, when given, is advanced by one per row of F (at 100k patches and 1.6e9 non-zeros
// the pass takes minutes: its reads of F_ji are scattered over the whole matrix).
ReciprocityStats reciprocity_stats(const CsrMatrix& F, const Scene& scene, Progress* progress = nullptr);

}  // namespace ffcube
