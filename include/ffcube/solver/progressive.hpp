// Progressive refinement (Cohen, Chen, Wallace, Greenberg 1988, "sorting and shooting"), with
// optional over-relaxation (overshooting) and a bounded row cache, as a stepping API so that a
// viewer can interleave shots with frames:
//
//   ProgressiveSolver solver(scene, provider, options);
//   while (solver.status() == StopReason::Running) { solver.step({.seconds = 0.01}); draw(solver.radiosity()); }
//
// Deterministic: the same scene, rows and options give the same B bit for bit, however the shots
// are split into steps and however many threads the provider uses.
#pragma once

#include <cmath>
#include <cstdint>
#include <limits>
#include <memory>
#include <span>

#include "ffcube/solver/solver.hpp"

namespace ffcube {

// How much one step() may do; it stops at whichever comes first (and at a stop reason). At least
// one batch of shots is done per call even when the time budget is 0, so a step always advances.
struct StepBudget {
    std::uint64_t max_shots = std::numeric_limits<std::uint64_t>::max();
    double seconds = INFINITY;
};

class ProgressiveSolver {
public:
    // Validates options and materials (InputError: see solve_radiosity). scene and provider are
    // referenced, not copied, and must outlive the solver; no row is computed here.
    ProgressiveSolver(const Scene& scene, RowProvider& provider, const SolverOptions& options);
    ~ProgressiveSolver();
    ProgressiveSolver(const ProgressiveSolver&) = delete;
    ProgressiveSolver& operator=(const ProgressiveSolver&) = delete;

    // Shoots within the budget; returns status(). Throws InputError if a row arriving from the
    // provider breaks the stiffness rule (the solver keeps its state up to the previous shot).
    StopReason step(const StepBudget& budget);
    // Steps until a stop reason.
    StopReason run();
    StopReason status() const;

    // B per patch (RGB), without the ambient term.
    std::span<const Vec3> radiosity() const;
    // ΔB per patch: radiosity received but not yet shot (negative after an overshoot).
    std::span<const Vec3> unshot_radiosity() const;
    // Σ_i A_i |ΔB_i| summed over channels / emitted power (1 at the start, 0 when all is shot).
    double unshot_fraction() const;
    // Cohen's ambient radiosity: (Σ_i A_i ΔB_i / Σ_i A_i) / (1 − ρ̄), ρ̄ the area-weighted mean
    // reflectance, per channel; for display only (add ρ_i × ambient to B_i).
    Vec3 ambient() const;
    std::uint64_t shots() const;
    EnergyBalance energy() const;
    RowCacheStats cache_stats() const;
    // The row of patch i if the row cache holds it (now most recently used), else nullptr; valid
    // until the next step(). For solve_radiosity's stiff finish.
    const SparseRow* cached_row(std::uint32_t i);
    // Whether the provider was ever asked for row i, and the largest sum of any row received.
    bool row_ever_computed(std::uint32_t i) const;
    double max_row_sum() const;
    // Snapshot of everything in SolveResult form (history included).
    SolveResult result() const;

    // Back to B = ΔB = E and no shots, as if just constructed. The row cache and its counters are
    // kept: rows depend only on the geometry, so a restart re-shoots from memory.
    void reset();

private:
    struct Impl;
    std::unique_ptr<Impl> impl_;
};

}  // namespace ffcube
