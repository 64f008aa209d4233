#include "ffcube/geometry/quadrature.hpp"

#include <glm/geometric.hpp>

#include <cmath>
#include <utility>
#include <numbers>

namespace ffcube {

GaussRule gauss_legendre(int n) {
    const auto size = static_cast<std::size_t>(n);
    GaussRule r{std::vector<double>(size), std::vector<double>(size)};
    for (std::size_t i = 0; i < size; ++i) {
        double z = std::cos(std::numbers::pi * (static_cast<double>(i) + 0.75) / (n + 0.5));
        double dp = 1.0;
        for (int it = 0; it < 100; ++it) {
            double p0 = 1.0, p1 = z;
            for (int k = 2; k <= n; ++k) {
                const double p2 = ((2.0 * k - 1.0) * z * p1 - (k - 1.0) * p0) / k;
                p0 = p1;
                p1 = p2;
            }
            dp = n * (z * p1 - p0) / (z * z - 1.0);
            const double dz = p1 / dp;
            z -= dz;
            if (std::abs(dz) <= 1e-16) break;
        }
        r.x[i] = z;
        r.w[i] = 2.0 / ((1.0 - z * z) * dp * dp);
    }
    return r;
}


void patch_quadrature(std::span<const Vec3> P, int n, std::vector<Vec3>& pts, std::vector<double>& wts) {
    pts.clear();
    wts.clear();
    if (P.size() == 3 && n == 2) {
        const double a = 2.0 / 3.0, b = 1.0 / 6.0;
        for (const auto& [s, t] : {std::pair{b, b}, std::pair{a, b}, std::pair{b, a}}) {
            pts.push_back(P[0] + s * (P[1] - P[0]) + t * (P[2] - P[0]));
            wts.push_back(1.0 / 3.0);
        }
        return;
    }
    const GaussRule g = gauss_legendre(n);
    double wsum = 0;
    for (std::size_t a = 0; a < g.x.size(); ++a)
        for (std::size_t b = 0; b < g.x.size(); ++b) {
            const double u = 0.5 * (1 + g.x[a]), v = 0.5 * (1 + g.x[b]);
            const double w = g.w[a] * g.w[b];
            if (P.size() == 4) {
                const Vec3 du = (1 - v) * (P[1] - P[0]) + v * (P[2] - P[3]);
                const Vec3 dv = (1 - u) * (P[3] - P[0]) + u * (P[2] - P[1]);
                pts.push_back((1 - u) * (1 - v) * P[0] + u * (1 - v) * P[1] + u * v * P[2] + (1 - u) * v * P[3]);
                wts.push_back(w * glm::length(glm::cross(du, dv)));
            } else {
                // (s, t) = (u, v (1 − u)): Jacobian (1 − u) times the triangle's.
                pts.push_back(P[0] + u * (P[1] - P[0]) + v * (1 - u) * (P[2] - P[0]));
                wts.push_back(w * (1 - u));
            }
            wsum += wts.back();
        }
    for (double& w : wts) w /= wsum;
}

}  // namespace ffcube
