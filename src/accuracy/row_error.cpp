// Terms of the per-row error estimate (see row_error.hpp).
#include "accuracy/row_error.hpp"

#include <glm/geometric.hpp>

#include <cmath>

namespace ffcube::accuracy {

double RowErrorModel::midpoint(std::uint32_t j, double f) const {
    const Vec3 r = scene.patches[j].centroid - sender.centroid;
    const double m = sender.size * sender.size / glm::dot(r, r) / 12.0;
    if (sampled_row) return f * m * m;  // the 2 × 2 rule's residual, about the square
    if (!quadrature) return 0.0;        // the inner provider samples the whole sender (ray caster)
    return f * m;
}

double RowErrorModel::noise(double f) const {
    double e = 0;
    if (pixel_delta_ff > 0) {
        // About 4√P pixels on the outline of a receiver covering P pixels, each off by a
        // uniform fraction of a pixel: σ = ΔF √(4√P / 12)... taken as ΔF √(4√P / 6) (the
        // pixels of an outline are not independent).
        const double dF = pixel_delta_ff;
        e += dF * std::sqrt(4.0 * std::sqrt(f / dF) / 6.0);
    }
    if (rays > 0) e += std::sqrt(f / rays);
    return e;
}

}  // namespace ffcube::accuracy
