// The range check of a corrected row (see row_range.hpp).
#include "accuracy/row_range.hpp"

#include <cmath>

#include "accuracy/rebalance.hpp"

namespace ffcube::accuracy {

double row_range_tolerance(bool keep_closed_rows, double error_estimate) {
    if (keep_closed_rows || !(error_estimate > 0) || !std::isfinite(error_estimate)) return kClosedRowTolerance;
    return kClosedRowTolerance + error_estimate;
}

bool row_in_range(std::span<const double> values, double tol) {
    double sum = 0;
    for (const double v : values) {
        if (!std::isfinite(v) || v < 0.0 || v > 1.0 + tol) return false;
        sum += v;
    }
    return sum <= 1.0 + tol;
}

}  // namespace ffcube::accuracy
