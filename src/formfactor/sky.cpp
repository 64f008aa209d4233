#include "ffcube/formfactor/sky.hpp"

#include <algorithm>

#include "ffcube/core/error.hpp"

namespace ffcube {

std::vector<double> sky_view_factors(const CsrMatrix& F) {
    FFCUBE_CHECK_MSG(F.rows_filled() == F.size(), "sky_view_factors needs every row of the matrix");
    std::vector<double> sums(F.size());
    for (std::uint32_t i = 0; i < F.size(); ++i) sums[i] = F.row(i).sum();
    return sky_view_factors(std::span<const double>(sums));
}

std::vector<double> sky_view_factors(std::span<const double> row_sums) {
    std::vector<double> svf(row_sums.size());
    for (std::size_t i = 0; i < row_sums.size(); ++i) svf[i] = std::max(0.0, 1.0 - row_sums[i]);
    return svf;
}

std::vector<double> object_areas(const Scene& scene) {
    std::vector<double> area(scene.objects.size(), 0.0);
    for (const Patch& p : scene.patches) area[p.object] += p.area;
    return area;
}

std::vector<double> object_means(const std::vector<double>& per_patch, const Scene& scene) {
    FFCUBE_CHECK(per_patch.size() == scene.size());
    std::vector<double> sum(scene.objects.size(), 0.0);
    for (std::size_t i = 0; i < scene.size(); ++i) sum[scene.patches[i].object] += scene.patches[i].area * per_patch[i];
    const std::vector<double> area = object_areas(scene);
    for (std::size_t a = 0; a < sum.size(); ++a) sum[a] = area[a] > 0.0 ? sum[a] / area[a] : 0.0;
    return sum;
}

SkyStats sky_stats(const std::vector<double>& svf, const Scene& scene) {
    FFCUBE_CHECK(svf.size() == scene.size());
    SkyStats s;
    if (svf.empty()) return s;
    s.min = *std::min_element(svf.begin(), svf.end());
    s.max = *std::max_element(svf.begin(), svf.end());
    double sum = 0.0, weighted = 0.0, area = 0.0;
    for (std::size_t i = 0; i < svf.size(); ++i) {
        sum += svf[i];
        weighted += scene.patches[i].area * svf[i];
        area += scene.patches[i].area;
    }
    s.mean = sum / static_cast<double>(svf.size());
    s.area_weighted_mean = area > 0.0 ? weighted / area : 0.0;
    return s;
}

}  // namespace ffcube
