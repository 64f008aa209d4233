// Gauss–Legendre quadrature: used by the analytic form factors and by tests that integrate the
// defining integrals independently.
#pragma once

#include <span>
#include <vector>

#include "ffcube/geometry/polygon.hpp"

namespace ffcube {

// n-point rule on [-1, 1]: nodes x and weights w (Σ w = 2), exact for polynomials of degree
// 2n − 1. Nodes by Newton's method on P_n from Tricomi's initial guesses, converged to rounding.
struct GaussRule {
    std::vector<double> x, w;
};
GaussRule gauss_legendre(int n);

// Quadrature points on a planar patch (3 or 4 vertices, a quad's corners in order), weights
// summing to 1: an n × n Gauss–Legendre tensor rule on a quad (weights by the bilinear
// Jacobian); on a triangle the symmetric 3-point degree-2 rule for n = 2, a collapsed (Duffy)
// n × n Gauss rule otherwise. The sender quadrature of the near-field correction and the
// hemicube's sub-hemicubes use the same points (n = 2).
void patch_quadrature(std::span<const Vec3> polygon, int n, std::vector<Vec3>& points, std::vector<double>& weights);

}  // namespace ffcube
