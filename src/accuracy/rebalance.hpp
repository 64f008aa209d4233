// Internal to the accuracy layer. One job: closed rows stay closed and no row exceeds 1
// (docs/accuracy.md, 3.): when a row is closed, or the correction pushed it above 1, its
// entries share one factor that makes it sum to 1 (normally only the non-exact ones).
#pragma once

#include <cstdint>
#include <span>

namespace ffcube::accuracy {

// An inner row whose sum is within this of 1 counts as closed. Float storage of a hemicube
// row's entries (2^-24 relative each) moves a closed row's sum by up to 6e-8, so the line must
// be above that; a row open by less than 1e-7 (a few pixels at grazing angles) is changed by
// at most that much when rebalanced to 1.
constexpr double kClosedRowTolerance = 1e-7;

// Whether a row is closed: a measured row when its inner sum is 1 within kClosedRowTolerance; a
// row made without measuring (analytic) when its analytic sum is 1 within its values' own error
// bounds (twice analytic_error), or kClosedRowTolerance if that is larger.
struct ClosedTest {
    bool analytic = false;
    double inner_sum = 0;       // for a measured row
    double analytic_error = 0;  // for an analytic row: NearAnalysis::far_error
    // For a measured row: what its measure may leave open in a closed scene, beyond
    // kClosedRowTolerance. A row of R rays refined to a tolerance: 2/R, two rays that float
    // rounding lost at a seam (a closed cube's rows lose about 1e-5 of their rays so); R ≥ 3/E,
    // so closing such a row moves it by less than the target (and the move joins its estimate).
    double measured_tolerance = 0;
};

struct Rebalance {
    bool closed = false;   // the row counts as closed
    bool applied = false;  // the factor was applied (closed, or capped at 1)
    double factor = 1;
    double moved = 0;  // Σ |change| of the entries (the row estimate's term)
};

// Rebalances values in place. A factor beyond 1 ± 0.1 is refused (nothing changes): where the
// non-exact entries are too few for the change, every entry shares it instead.
Rebalance rebalance_row(std::span<double> values, std::span<const std::uint8_t> is_exact, const ClosedTest& test);

}  // namespace ffcube::accuracy
