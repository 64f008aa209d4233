// Sky view factors of an open scene: the share of a patch's hemisphere through which it sees no
// surface of the scene. SVF_i = 1 − Σ_j F_ij: the energy leaving patch i diffusely that arrives at
// no patch escapes (to the sky of an urban scene, to the opening of a cavity). Pure CPU.
#pragma once

#include <span>
#include <vector>

#include "ffcube/formfactor/sparse.hpp"
#include "ffcube/scene/scene.hpp"

namespace ffcube {

// Per patch: 1 − Σ_j F_ij, clamped at 0 (a row summing above 1 by rounding sees no sky).
// Every row of F must be filled.
std::vector<double> sky_view_factors(const CsrMatrix& F);
// The same from each row's sum (RowView::sum, as F.row(i).sum()): for rows that were streamed.
std::vector<double> sky_view_factors(std::span<const double> row_sums);

// Total patch area per object (scene units²).
std::vector<double> object_areas(const Scene& scene);

// Per object: the area-weighted mean of its patches' values, Σ_{i∈a} A_i v_i / Σ_{i∈a} A_i: for
// sky view factors, the share of the energy leaving object a diffusely that escapes.
std::vector<double> object_means(const std::vector<double>& per_patch, const Scene& scene);

struct SkyStats {
    double min = 0.0, mean = 0.0, max = 0.0;  // over patches; mean is unweighted
    double area_weighted_mean = 0.0;          // Σ A_i SVF_i / Σ A_i
};
SkyStats sky_stats(const std::vector<double>& svf, const Scene& scene);

}  // namespace ffcube
