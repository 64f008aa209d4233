// Gauss–Legendre quadrature: used by the analytic form factors and by tests that integrate the
// defining integrals independently.
#pragma once

#include <vector>

namespace ffcube {

// n-point rule on [-1, 1]: nodes x and weights w (Σ w = 2), exact for polynomials of degree
// 2n − 1. Nodes by Newton's method on P_n from Tricomi's initial guesses, converged to rounding.
struct GaussRule {
    std::vector<double> x, w;
};
GaussRule gauss_legendre(int n);

}  // namespace ffcube
