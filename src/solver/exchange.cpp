#include "ffcube/solver/exchange.hpp"

#include "ffcube/core/error.hpp"
#include "ffcube/solver/linear.hpp"

namespace ffcube {

std::vector<std::vector<double>> hottel_exchange_factors(const std::vector<std::vector<double>>& G,
                                                         const std::vector<double>& area,
                                                         const std::vector<double>& emissivity) {
    const auto n = static_cast<std::uint32_t>(G.size());
    FFCUBE_CHECK(area.size() == n && emissivity.size() == n);
    // A = I − diag(ρ) G: radiosity J = ε E_b + ρ (G J).
    DenseMatrix a(n);
    for (std::uint32_t i = 0; i < n; ++i) {
        FFCUBE_CHECK(G[i].size() == n);
        const double rho = 1.0 - emissivity[i];
        for (std::uint32_t j = 0; j < n; ++j) a(i, j) = (i == j ? 1.0 : 0.0) - rho * G[i][j];
    }
    std::vector<std::uint32_t> perm;
    lu_factor(a, perm, "the exchange-factor system (I - rho F) of the View3D output (emit=1)");
    std::vector<std::vector<double>> X(n, std::vector<double>(n, 0.0));
    std::vector<double> J(n), scratch(n);
    for (std::uint32_t src = 0; src < n; ++src) {
        std::fill(J.begin(), J.end(), 0.0);
        J[src] = emissivity[src];
        lu_solve(a, perm, J, scratch);
        for (std::uint32_t m = 0; m < n; ++m) {
            double h = 0.0;  // irradiance of m: H_m = Σ_l G_ml J_l
            for (std::uint32_t l = 0; l < n; ++l) h += G[m][l] * J[l];
            X[src][m] = emissivity[m] * area[m] * h / area[src];
        }
    }
    return X;
}

}  // namespace ffcube
