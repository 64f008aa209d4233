// The sender quadrature's rescaling of one entry (see sender_quadrature.hpp).
#include "accuracy/sender_quadrature.hpp"

#include <glm/geometric.hpp>

#include <algorithm>
#include <cmath>

#if defined(__SSE2__)
#include <emmintrin.h>
#endif

#include "ffcube/core/error.hpp"
#include "ffcube/geometry/analytic.hpp"
#include "ffcube/geometry/quadrature.hpp"

namespace ffcube::accuracy {

namespace {

// Beyond this many sizes the quadrature ratio uses the point kernel cosθ_i cosθ_j / r⁴ (see
// rescale): its relative error on the correction is about (size_j/d)² ≤ 1/36 at 6 sizes, where
// the correction itself is ≈ (size_i/d)²/24 ≤ 1e-3 of F_ij: 3e-5 of F_ij.
constexpr double kPointKernelK = 6.0;
// The quadrature ratio is a small correction where the midpoint rule is sound. A ratio far
// from 1 means j straddles i's horizon or the centre sees little of it (the hemicube's value
// is then pixels at a grazing angle, not a midpoint value): scaling it would amplify pixel
// error (rows of the Cornell box grew to 1.098). Such entries are left alone.
constexpr double kMaxRatioChange = 0.25;

}  // namespace

bool sender_quadrature_needed(const PatchSet& patches, const NearFieldOptions& options, std::uint32_t i,
                              std::span<const std::uint32_t> columns) {
    const Patch& pi = patches.scene.patches[i];
    for (std::uint32_t j : columns) {
        const Patch& pj = patches.scene.patches[j];
        const Vec3 r = pj.centroid - pi.centroid;
        const double lim = options.quadrature_k * std::max(pi.size, pj.size);
        if (glm::dot(r, r) < lim * lim) return true;
    }
    return false;
}

SenderQuadrature::SenderQuadrature(const PatchSet& patches, const NearFieldOptions& options, std::uint32_t i,
                                   const RowErrorModel& error, bool needed, std::vector<Vec3>& points,
                                   std::vector<double>& weights)
    : patches_(patches), options_(options), pi_(patches.scene.patches[i]), error_(error), needed_(needed) {
    if (needed) {
        patch_quadrature(patches.polys[i].span(), 2, points, weights);
        qp_ = points;
        qw_ = weights;
        // The point kernel's points: the centroid, then the rule's (the 2 × 2 rule: 3 or 4),
        // padded to an even count with the centroid (point_kernels works two at a time; the
        // padding's values are not used).
        FFCUBE_CHECK(qp_.size() + 1 <= kMaxKernelPoints);
        npts_ = qp_.size() + 1;
        for (std::size_t k = 0; k < kMaxKernelPoints; ++k) {
            const Vec3& x = (k >= 1 && k <= qp_.size()) ? qp_[k - 1] : pi_.centroid;
            px_[k] = x.x;
            py_[k] = x.y;
            pz_[k] = x.z;
        }
    }
}

SenderQuadrature::Entry SenderQuadrature::ratio(double f, double r) const {
    if (!(std::abs(r - 1.0) <= kMaxRatioChange))
        return {f, std::abs(r - 1.0) * f, false};  // left alone: off by about the ratio it needed
    // What remains is the 2 × 2 rule's error, O((h/d)⁴): the square of the midpoint one.
    const double m = std::abs(r - 1.0);
    return {f * r, f * r * m * m, true};
}

// The point kernel cosθ_i cosθ_j / r⁴ from each of the first npts_ points (rounded up to even)
// to receiver j (centroid c, normal nj), into out. The same operations in the same order as
// the scalar form `max(0, n_i·r) · max(0, −n_j·r) / (r²·r²)`, r = c − x, glm's dot summing
// x, y, then z: so the same bits, two points at a time (SSE2 is IEEE double, like the scalar
// unit; nothing is contracted to FMA on the x86-64 baseline).
void SenderQuadrature::point_kernels(const Vec3& c, const Vec3& nj, double* out) const {
    const Vec3& ni = pi_.normal;
#if defined(__SSE2__)
    const __m128d cx = _mm_set1_pd(c.x), cy = _mm_set1_pd(c.y), cz = _mm_set1_pd(c.z);
    const __m128d nix = _mm_set1_pd(ni.x), niy = _mm_set1_pd(ni.y), niz = _mm_set1_pd(ni.z);
    const __m128d njx = _mm_set1_pd(nj.x), njy = _mm_set1_pd(nj.y), njz = _mm_set1_pd(nj.z);
    const __m128d zero = _mm_setzero_pd();
    const __m128d sign = _mm_set1_pd(-0.0);
    for (std::size_t k = 0; k < npts_; k += 2) {
        const __m128d rx = _mm_sub_pd(cx, _mm_load_pd(&px_[k]));
        const __m128d ry = _mm_sub_pd(cy, _mm_load_pd(&py_[k]));
        const __m128d rz = _mm_sub_pd(cz, _mm_load_pd(&pz_[k]));
        const __m128d di = _mm_add_pd(_mm_add_pd(_mm_mul_pd(nix, rx), _mm_mul_pd(niy, ry)), _mm_mul_pd(niz, rz));
        const __m128d dj = _mm_add_pd(_mm_add_pd(_mm_mul_pd(njx, rx), _mm_mul_pd(njy, ry)), _mm_mul_pd(njz, rz));
        // maxpd(v, 0) is v > 0 ? v : 0, as std::max(0.0, v) (NaN and −0 give +0 in both).
        const __m128d a = _mm_max_pd(di, zero);
        const __m128d b = _mm_max_pd(_mm_xor_pd(dj, sign), zero);
        const __m128d r2 = _mm_add_pd(_mm_add_pd(_mm_mul_pd(rx, rx), _mm_mul_pd(ry, ry)), _mm_mul_pd(rz, rz));
        _mm_store_pd(out + k, _mm_div_pd(_mm_mul_pd(a, b), _mm_mul_pd(r2, r2)));
    }
#else
    for (std::size_t k = 0; k < npts_; ++k) out[k] = point_kernel_scalar(c, nj, {px_[k], py_[k], pz_[k]});
#endif
}

double SenderQuadrature::point_kernel_scalar(const Vec3& c, const Vec3& nj, const Vec3& x) const {
    const Vec3 r = c - x;
    const double r2 = glm::dot(r, r);
    return std::max(0.0, glm::dot(pi_.normal, r)) * std::max(0.0, -glm::dot(nj, r)) / (r2 * r2);
}

SenderQuadrature::Entry SenderQuadrature::rescale(std::uint32_t j, double f) const {
    const Patch& pi = pi_;
    const Patch& pj = patches_.scene.patches[j];
    const Vec3 r0 = pj.centroid - pi.centroid;
    const double r2 = glm::dot(r0, r0);
    // The entry as it was, with the midpoint rule's error (RowErrorModel::midpoint from the same
    // r², computed only where it is returned).
    const auto kept = [&] { return Entry{f, error_.midpoint_at(r2, f), false}; };
    if (!needed_) return kept();
    const double d = std::sqrt(r2);  // glm::length(r0)
    const double size = std::max(pi.size, pj.size);
    if (d >= options_.quadrature_k * size) return kept();
    // Near pairs were replaced or refused: a refused one may be occluded, and its hemicube value
    // is kept as it is (the midpoint rule's error there reaches ~5%: the issue's −4.7% on
    // squares sharing an edge).
    if (d < options_.k * size) return {f, 0.05 * f, false};
    const std::size_t nq = qp_.size();
    if (d >= kPointKernelK * size) {
        // Far: the receiver as a point at its centroid (see kPointKernelK); a few flops per
        // point instead of Lambert's contour.
        alignas(16) double kv[kMaxKernelPoints];
        point_kernels(pj.centroid, pj.normal, kv);
        const double mid = kv[0];
        if (!(mid > 0)) return kept();
        double q = 0;
        for (std::size_t k = 0; k < nq; ++k) q += qw_[k] * kv[k + 1];
        return ratio(f, q / mid);
    }
    const auto poly = patches_.polys[j].span();
    // Lambert's contour; without clipping or checks when all of j is in front of the plane
    // through x (then nothing needs clipping), which is nearly always the case here.
    const auto lambert = [&](const Vec3& x) {
        for (const Vec3& v : poly)
            if (!(glm::dot(v - x, pi.normal) > 0)) return ff_point_polygon(x, pi.normal, poly);
        return ff_point_polygon_unclipped(x, pi.normal, poly);
    };
    const double mid = lambert(pi.centroid);
    if (!(mid > 0)) return kept();  // the inner provider saw j where the centre sees it edge-on: keep
    double q = 0;
    // One-sided: points behind j's plane (a patch that j stands on, cut by j's base) see its
    // back, which ff_point_polygon would count.
    for (std::size_t k = 0; k < nq; ++k)
        if (glm::dot(qp_[k] - pj.centroid, pj.normal) > 0) q += qw_[k] * lambert(qp_[k]);
    return ratio(f, q / mid);
}

}  // namespace ffcube::accuracy
