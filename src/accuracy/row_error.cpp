// Terms of the per-row error estimate (see row_error.hpp).
#include "accuracy/row_error.hpp"

#include <glm/geometric.hpp>

#include <cmath>

#if defined(__SSE2__)
#include <emmintrin.h>
#endif

namespace ffcube::accuracy {

double RowErrorModel::midpoint(std::uint32_t j, double f) const {
    const Vec3 r = scene.patches[j].centroid - sender.centroid;
    return midpoint_at(glm::dot(r, r), f);
}

double RowErrorModel::midpoint_at(double r2, double f) const {
    const double m = sender.size * sender.size / r2 / 12.0;
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

// The scalar form's operations in its order, 0 + a (+ b) included: IEEE sqrt and division are
// correctly rounded in SSE2's packed forms as in its scalar ones.
void RowErrorModel::noise(std::span<const double> f, double* out) const {
    std::size_t a = 0;
#if defined(__SSE2__)
    const __m128d dF = _mm_set1_pd(pixel_delta_ff), four = _mm_set1_pd(4.0), six = _mm_set1_pd(6.0);
    const __m128d nrays = _mm_set1_pd(rays);
    for (; a + 2 <= f.size(); a += 2) {
        const __m128d v = _mm_loadu_pd(f.data() + a);
        __m128d e = _mm_setzero_pd();
        if (pixel_delta_ff > 0) {
            const __m128d inner = _mm_div_pd(_mm_mul_pd(four, _mm_sqrt_pd(_mm_div_pd(v, dF))), six);
            e = _mm_add_pd(e, _mm_mul_pd(dF, _mm_sqrt_pd(inner)));
        }
        if (rays > 0) e = _mm_add_pd(e, _mm_sqrt_pd(_mm_div_pd(v, nrays)));
        _mm_storeu_pd(out + a, e);
    }
#endif
    for (; a < f.size(); ++a) out[a] = noise(f[a]);
}

}  // namespace ffcube::accuracy
