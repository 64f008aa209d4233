#include "ffcube/geometry/quadrature.hpp"

#include <cmath>
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

}  // namespace ffcube
