// Hottel's total exchange factors ("script F", Hottel & Sarofim, Radiative Transfer, 1967,
// pp. 84–86), as View3D writes them with emit=1: the share of the energy that surface n emits
// which surface m absorbs, reflections by grey diffuse surfaces included.
#pragma once

#include <vector>

namespace ffcube {

// G[n][m]: form factors between N surfaces (fraction of the energy leaving n that arrives at m);
// area[n] > 0; emissivity[n] in (0, 1] (reflectance ρ = 1 − ε). Returns X with
//   X[n][m] = ε_m A_m H_m / A_n,  H = G J,  (I − diag(ρ) G) J = ε_n e_n,
// i.e. the power absorbed by m per unit area of n when only n emits, at unit blackbody exitance.
// In a closed enclosure (rows of G summing to 1) row n sums to ε_n. Dense LU, O(N³).
// Throws InputError when the system is singular (an enclosure of perfect reflectors).
std::vector<std::vector<double>> hottel_exchange_factors(const std::vector<std::vector<double>>& G,
                                                         const std::vector<double>& area,
                                                         const std::vector<double>& emissivity);

}  // namespace ffcube
