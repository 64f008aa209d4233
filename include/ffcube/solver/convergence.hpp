// When to stop: the stop reasons, the divergence detector, the bounded convergence history, and
// the sweep driver that iterates Jacobi or Gauss–Seidel on one or more systems until the summed
// weighted residual is small, the sweep limit is reached, or the residual grows.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <functional>
#include <span>
#include <string>
#include <vector>

#include "ffcube/solver/linear.hpp"

namespace ffcube {

enum class StopReason {
    Running,         // the stepping API has not reached a stop yet
    Converged,       // unshot (residual) power ≤ tolerance × emitted power
    IterationLimit,  // max_iterations shots or sweeps done first
    Diverged,        // unshot power grew over a window (or became non-finite): see DivergenceMonitor
    NothingToDo,     // no emitters: B = 0
};
// "running", "converged", "iteration_limit", "diverged", "nothing_to_do" (used in reports).
std::string to_string(StopReason r);

// Watches a quantity that should go to zero (the unshot or residual fraction) and says when it is
// diverging: it is not finite, or it has not improved on its best value for `window` updates and
// is now more than `growth` times that best. Both conditions together so that the transient rise
// of a converging solve (overshooting makes unshot energy negative somewhere and so raises its
// absolute sum for a while; non-reciprocal rows can raise it a little) is not taken for
// divergence, while a geometric blow-up is caught after about window + log(growth)/log(rate)
// updates: nothing loops forever.
class DivergenceMonitor {
public:
    DivergenceMonitor(std::uint64_t window, double growth) : window_(window), growth_(growth) {}
    // Feeds the next value; true when diverging.
    bool update(double value);

private:
    std::uint64_t window_;
    double growth_;
    double best_ = INFINITY;
    std::uint64_t since_best_ = 0;
};

// (seconds since the solve started, unshot fraction) pairs.
struct ConvergenceSample {
    double seconds = 0.0;
    double unshot_fraction = 0.0;
};

// Keeps at most `capacity` samples of a run of any length: every `stride`-th offered sample is
// kept; when full, every other kept sample is dropped and the stride doubles. So the history
// spans the whole run at uniform (in iteration count) spacing, and the last offered sample is
// always kept (finish()).
class ConvergenceHistory {
public:
    explicit ConvergenceHistory(std::size_t capacity);
    void offer(double seconds, double unshot_fraction);
    // Appends the final state if it is not the last sample kept.
    void finish(double seconds, double unshot_fraction);
    const std::vector<ConvergenceSample>& samples() const { return samples_; }
    void clear();

private:
    std::size_t capacity_;
    std::uint64_t stride_ = 1;
    std::uint64_t offered_ = 0;
    std::vector<ConvergenceSample> samples_;
};

enum class Sweep { Jacobi, GaussSeidel };

struct SweepControl {
    Sweep sweep = Sweep::GaussSeidel;
    double tolerance = 1e-4;            // stop when Σ_k Σ_i w_i |r_ki| ≤ tolerance × reference
    std::uint64_t max_sweeps = 10000;
    std::uint64_t divergence_window = 3;  // sweeps (see DivergenceMonitor)
    double divergence_growth = 1e3;
    // Stagnation: every stagnation_window sweeps the fraction must have fallen below
    // (1 − stagnation_progress) × its value a window earlier, else the solve stops as diverged
    // (stagnated). A spectral radius of exactly 1 (ρ = 1 in a closed scene) keeps the residual
    // constant, which the growth test never sees; a converging iteration with spectral radius s
    // falls by s^window, so only s > 1 − 1e-8 is mistaken for it.
    std::uint64_t stagnation_window = 100;
    double stagnation_progress = 1e-6;
};

// A sweep of some rows only: this process's block of a solve split over processes
// (solver/row_blocks.hpp). After each sweep, share(x[k]) fills every other block's rows of x[k]
// with its owner's newest values; total(v) is the sum of v over all blocks, the same on each.
// Gauss–Seidel is then Gauss–Seidel inside a block and Jacobi between blocks (docs/scaling.md).
struct SweepRange {
    std::uint32_t first = 0, last = 0;
    std::function<void(std::span<double> x)> share;
    std::function<double(double)> total;
};

struct SweepOutcome {
    StopReason stop = StopReason::Running;
    std::uint64_t sweeps = 0;
    double residual_fraction = 0.0;  // Σ_k Σ_i w_i |r_ki| / reference after the last sweep
    bool stagnated = false;          // stopped as diverged by the stagnation rule
};

// Sweeps several independent systems of the same size together (radiosity's three channels share
// one stopping rule): after each sweep of every system it measures
//   fraction = Σ_k Σ_i weights[i] |r_ki| / reference
// and calls on_sweep(sweeps, fraction) (may be empty; also called once with sweeps = 0 for the
// start vector). x[k] is system k's start vector and result.
// reference > 0. Allocates its Jacobi scratch once, before the first sweep. With a range, only
// its rows are swept and measured (SweepRange); every block then takes the same decisions.
template <SweepSystem S>
SweepOutcome sweep_until(std::span<const S> systems, std::span<const std::span<double>> x,
                         std::span<const double> weights, double reference, const SweepControl& control,
                         const std::function<void(std::uint64_t, double)>& on_sweep,
                         const SweepRange* range = nullptr) {
    const std::uint32_t first = range ? range->first : 0;
    const auto last_of = [&](const S& s) { return range ? range->last : s.size(); };
    const auto fraction = [&] {
        double sum = 0.0;
        for (std::size_t k = 0; k < systems.size(); ++k)
            for (std::uint32_t i = first; i < last_of(systems[k]); ++i)
                sum += weights[i] * std::abs(residual(systems[k], i, x[k]));
        return (range ? range->total(sum) : sum) / reference;
    };
    std::vector<double> scratch(control.sweep == Sweep::Jacobi && !systems.empty() ? systems[0].size() : 0);
    DivergenceMonitor monitor(control.divergence_window, control.divergence_growth);
    SweepOutcome out;
    out.residual_fraction = fraction();
    if (on_sweep) on_sweep(0, out.residual_fraction);
    monitor.update(out.residual_fraction);
    double checkpoint = out.residual_fraction;
    while (true) {
        if (out.residual_fraction <= control.tolerance) {
            out.stop = StopReason::Converged;
            return out;
        }
        if (out.sweeps >= control.max_sweeps) {
            out.stop = StopReason::IterationLimit;
            return out;
        }
        for (std::size_t k = 0; k < systems.size(); ++k) {
            const std::uint32_t last = last_of(systems[k]);
            if (control.sweep == Sweep::Jacobi) {
                jacobi_sweep(systems[k], x[k], scratch, first, last);
                std::copy(scratch.begin() + first, scratch.begin() + last, x[k].begin() + first);
            } else {
                gauss_seidel_sweep(systems[k], x[k], first, last);
            }
            if (range) range->share(x[k]);
        }
        ++out.sweeps;
        out.residual_fraction = fraction();
        if (on_sweep) on_sweep(out.sweeps, out.residual_fraction);
        if (monitor.update(out.residual_fraction)) {
            out.stop = StopReason::Diverged;
            return out;
        }
        if (control.stagnation_window > 0 && out.sweeps % control.stagnation_window == 0) {
            if (!(out.residual_fraction < (1.0 - control.stagnation_progress) * checkpoint) &&
                !(out.residual_fraction <= control.tolerance)) {
                out.stop = StopReason::Diverged;
                out.stagnated = true;
                return out;
            }
            checkpoint = out.residual_fraction;
        }
    }
}

}  // namespace ffcube
