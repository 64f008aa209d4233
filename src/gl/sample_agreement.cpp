// Whether 2 × 2 sub-hemicubes agree well enough to stop there (see sample_agreement.hpp).
#include "gl/sample_agreement.hpp"

#include <glm/common.hpp>
#include <glm/geometric.hpp>

#include <algorithm>
#include <cmath>

#include "ffcube/geometry/analytic.hpp"

namespace ffcube {

namespace {

// 3σ of the pixel noise on an entry of value f (accuracy/row_error.cpp's model: about 4√P
// outline pixels of a receiver covering P pixels, each off by a fraction of a pixel).
double noise3(double f, double dF) {
    if (!(dF > 0) || !(f > 0)) return 0.0;
    return 3.0 * dF * std::sqrt(4.0 * std::sqrt(f / dF) / 6.0);
}

// Distance from x to the bounding box of polygon v.
double box_distance(std::span<const Vec3> v, const Vec3& x) {
    Vec3 lo = v[0], hi = v[0];
    for (const Vec3& a : v) {
        lo = glm::min(lo, a);
        hi = glm::max(hi, a);
    }
    return glm::length(glm::max(glm::max(lo - x, x - hi), Vec3(0.0)));
}

// The 2 × 2 rule's error per unit of the centre's deviation d from the samples' interpolated
// visibility, on one-dimensional model integrands over [0, 1] (Gauss points 0.211 and 0.789,
// centre 0.5): a quadratic x², error 0 (the rule is exact to cubics), d = 0.083; a kink |x − ½|,
// error 0.039, d = 0.289 (ratio 0.13); a step at s in (0.211, 0.789), error |½ − s| < 0.289,
// d = 0.5 (ratio < 0.58). Taken: 0.6, above every case. (A step outside the points, s < 0.211,
// changes no sample and is seen by no rule of these points: error ≤ s · the entry.)
constexpr double kErrorPerDeviation = 0.6;

}  // namespace

SampleAgreement judge_samples(const Scene& scene, std::uint32_t p, std::span<const Vec3> points,
                              std::span<const double> weights, std::span<const SparseRow> rows,
                              const SparseRow& centre, const SampleAgreementOptions& options, SparseRow& out) {
    SampleAgreement a;
    out.clear();
    const std::size_t m = rows.size();
    const Patch& pi = scene.patches[p];
    const auto vi = scene.patch_vertices(p);
    const std::span<const Vec3> poly_i(vi.data(), pi.count);
    std::vector<std::size_t> at(m, 0);
    std::size_t at_c = 0;
    double sum = 0.0, centre_sum = 0.0;
    // Columns in increasing order: a merge of the sorted sample rows and the centre's.
    for (;;) {
        std::uint32_t j = at_c < centre.nnz() ? centre.col[at_c] : UINT32_MAX;
        for (std::size_t q = 0; q < m; ++q)
            if (at[q] < rows[q].nnz()) j = std::min(j, rows[q].col[at[q]]);
        if (j == UINT32_MAX) break;
        const auto vj = scene.patch_vertices(j);
        const std::span<const Vec3> poly_j(vj.data(), scene.patches[j].count);
        double vbar = 0.0, mean = 0.0, kernel = 0.0;
        for (std::size_t q = 0; q < m; ++q) {
            double r = 0.0;
            if (at[q] < rows[q].nnz() && rows[q].col[at[q]] == j) r = rows[q].val[at[q]++];
            const double u = ff_point_polygon(points[q], pi.normal, poly_j);
            const double v = u > 0 ? r / u : 0.0;
            vbar += weights[q] * v;
            kernel += weights[q] * u;
            mean += weights[q] * r;
        }
        double rc = 0.0;
        if (at_c < centre.nnz() && centre.col[at_c] == j) rc = centre.val[at_c++];
        centre_sum += rc;
        const double uc = ff_point_polygon(pi.centroid, pi.normal, poly_j);
        // The centre against the visibility interpolated from the samples (their mean), on j's
        // exact kernel from the centre: d = U_c (v_c − v̄).
        const double d = rc - vbar * uc;
        const double e = kErrorPerDeviation * std::abs(d);
        const double allowance = noise3(std::max(rc, vbar * uc), options.pixel_delta_ff);
        sum += d;
        if (e - allowance > a.worst_entry) {
            a.worst_entry = e - allowance;
            a.worst_col = j;
        }
        // A receiver within 2 sender sizes: the 2 × 2 rule's own residual on the kernel U, about
        // F·(h²/12d²)² (accuracy/row_error.cpp), is largest there (3.6e-4 on touching unit
        // squares at 90°; more for a facet much larger than the sender), and it is known: the
        // exact area-to-area factor minus the rule's Σ_q w_q U_q. It is added in proportion to
        // the mean visibility (all of it for a receiver seen whole: then the value is exact).
        if (box_distance(poly_j, pi.centroid) < 2.0 * pi.size) {
            mean += vbar * (ff_polygon_polygon(poly_i, poly_j) - kernel);
            ++a.exact_entries;
        }
        out.col.push_back(j);
        out.val.push_back(mean);
    }
    // The row sum's pixel noise: pixels that move between two patches leave the sum as it is;
    // only the outline of the sky (what the centre saw of nothing, 1 − Σ_j r_c(j)) moves it, one
    // receiver's noise rather than the entries' summed.
    a.worst_sum = kErrorPerDeviation * std::abs(sum) - noise3(std::max(0.0, 1.0 - centre_sum), options.pixel_delta_ff);
    a.refine = a.worst_entry > options.tolerance || a.worst_sum > options.tolerance;
    if (a.refine) out.clear();
    return a;
}

}  // namespace ffcube
