// Shared by the solver's sources: per-patch inputs taken from the Scene once (validated), the
// row checks of the stiffness rule, and the gathering / direct entry points.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "ffcube/formfactor/row_provider.hpp"
#include "ffcube/scene/scene.hpp"
#include "ffcube/solver/solver.hpp"

namespace ffcube::detail {

struct PatchInputs {
    std::vector<double> area;      // A_i > 0, scene units²
    std::vector<double> inv_area;  // 1 / A_i
    std::vector<Vec3> rho;         // Kd of the patch's material, each channel in [0, 1)
    std::vector<Vec3> emit;        // Ke of the patch's material, each channel ≥ 0
    Vec3 emitted{0.0};             // Σ_i E_i A_i per channel
    double emitted_total = 0.0;    // summed over channels
    double total_area = 0.0;
    Vec3 mean_rho{0.0};            // Σ_i ρ_i A_i / Σ_i A_i

    std::uint32_t size() const { return static_cast<std::uint32_t>(area.size()); }
};

// Reads and validates the scene against the provider. InputError when the provider's size differs,
// a patch has a non-positive or non-finite area, an object or material index is out of range, or a
// used material has Kd outside [0, 1) or Ke negative or not finite (the Kd ≥ 1 rule: see
// docs/solvers.md).
PatchInputs load_patches(const Scene& scene, const RowProvider& provider);

// "patch 12 (object 'floor', material 'white')" for messages.
std::string describe_patch(const Scene& scene, std::uint32_t i);

// Checks row i as it arrives from the provider and returns its sum (in double, in column order):
// every column < n and every value finite and ≥ 0 (InputError naming the provider otherwise), and
// the stiffness rule ρ_i × rowsum_i < 1 in every channel (InputError explaining that there is no
// steady state otherwise).
double check_row(const Scene& scene, const RowProvider& provider, std::uint32_t i, const SparseRow& row,
                 const Vec3& rho);

// SolveResult::error_bound and error_bound_relative from unshot_abs, radiosity, the materials and
// stiffness.max_row_sum (derivation in solver.cpp).
void set_error_bound(SolveResult& r, const PatchInputs& in);

// The result of a scene with no emitters: B = 0, stop reason nothing_to_do and its warning.
SolveResult nothing_to_do(const Scene& scene, SolverMethod method);

// Jacobi or Gauss–Seidel (options.method), and the dense LU solve.
SolveResult solve_sweeps(const Scene& scene, RowProvider& provider, const SolverOptions& options);
SolveResult solve_direct(const Scene& scene, RowProvider& provider, const SolverOptions& options);
// Progressive refinement that switches to a GMRES finish on stiff scenes (stiff.cpp).
SolveResult solve_shooting(const Scene& scene, RowProvider& provider, const SolverOptions& options);

}  // namespace ffcube::detail
