// Internal to the accuracy layer. One job: the last check of a corrected row before it leaves
// the layer (docs/robustness.md, "No row out of range"): every entry finite in [0, 1] and the
// sum at most 1, each within the row's tolerance. CorrectedRowProvider replaces a row that fails
// by the row as measured (valid by construction), or refuses it by name.
#pragma once

#include <span>

namespace ffcube::accuracy {

// The tolerance of a corrected row's range check.
//  - The entries are stored as floats (2^-24 relative each); a row summing to 1 in double then
//    sums to at most 1 + 6e-8 as stored: kClosedRowTolerance (1e-7, rebalance.hpp) covers that.
//  - With keep_closed_rows (the default) rebalance_row scales every row above 1 down to exactly 1
//    when the factor is within 1 ± 0.1; a row still above 1 + 1e-7 is one the correction pushed
//    more than 10% over: wrong, whatever its estimate says.
//  - Without it, a row may exceed 1 by its own error estimate (Σ_j |F_ij − exact_ij|, which
//    bounds how far its sum may be from the true sum, at most 1): the tolerance adds it.
double row_range_tolerance(bool keep_closed_rows, double error_estimate);

// Whether every value is finite and within [0, 1 + tol] and their sum (in double, as the
// entries stand) is at most 1 + tol.
bool row_in_range(std::span<const double> values, double tol);

}  // namespace ffcube::accuracy
