// The sender quadrature's rescaling of one entry (see sender_quadrature.hpp).
#include "accuracy/sender_quadrature.hpp"

#include <glm/geometric.hpp>

#include <algorithm>
#include <cmath>

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
    }
}

SenderQuadrature::Entry SenderQuadrature::ratio(double f, double r) const {
    if (!(std::abs(r - 1.0) <= kMaxRatioChange))
        return {f, std::abs(r - 1.0) * f, false};  // left alone: off by about the ratio it needed
    // What remains is the 2 × 2 rule's error, O((h/d)⁴): the square of the midpoint one.
    const double m = std::abs(r - 1.0);
    return {f * r, f * r * m * m, true};
}

SenderQuadrature::Entry SenderQuadrature::rescale(std::uint32_t j, double f) const {
    const Entry kept{f, error_.midpoint(j, f), false};
    if (!needed_) return kept;
    const Patch& pi = pi_;
    const Patch& pj = patches_.scene.patches[j];
    const double d = glm::length(pj.centroid - pi.centroid);
    const double size = std::max(pi.size, pj.size);
    if (d >= options_.quadrature_k * size) return kept;
    // Near pairs were replaced or refused: a refused one may be occluded, and its hemicube value
    // is kept as it is (the midpoint rule's error there reaches ~5%: the issue's −4.7% on
    // squares sharing an edge).
    if (d < options_.k * size) return {f, 0.05 * f, false};
    const std::size_t nq = qp_.size();
    if (d >= kPointKernelK * size) {
        // Far: the receiver as a point at its centroid (see kPointKernelK); a few flops per
        // point instead of Lambert's contour.
        const auto kernel = [&](const Vec3& x) {
            const Vec3 r = pj.centroid - x;
            const double r2 = glm::dot(r, r);
            return std::max(0.0, glm::dot(pi.normal, r)) * std::max(0.0, -glm::dot(pj.normal, r)) / (r2 * r2);
        };
        const double mid = kernel(pi.centroid);
        if (!(mid > 0)) return kept;
        double q = 0;
        for (std::size_t k = 0; k < nq; ++k) q += qw_[k] * kernel(qp_[k]);
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
    if (!(mid > 0)) return kept;  // the inner provider saw j where the centre sees it edge-on: keep
    double q = 0;
    // One-sided: points behind j's plane (a patch that j stands on, cut by j's base) see its
    // back, which ff_point_polygon would count.
    for (std::size_t k = 0; k < nq; ++k)
        if (glm::dot(qp_[k] - pj.centroid, pj.normal) > 0) q += qw_[k] * lambert(qp_[k]);
    return ratio(f, q / mid);
}

}  // namespace ffcube::accuracy
