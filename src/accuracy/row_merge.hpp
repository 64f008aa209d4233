// Internal to the accuracy layer. One job: merge an inner row with a row's analytic entries
// (columns in increasing order): analytic columns take their value (dropped when 0), the
// others the sender quadrature's rescaling, and each entry's error terms go to the estimate.
#pragma once

#include <cstdint>
#include <span>
#include <utility>
#include <vector>

#include "accuracy/row_error.hpp"
#include "accuracy/sender_quadrature.hpp"
#include "ffcube/accuracy/near_field.hpp"
#include "ffcube/formfactor/sparse.hpp"

namespace ffcube::accuracy {

struct MergedRow {
    SparseRow row;
    std::vector<std::uint8_t> is_exact;  // per entry of row: 1 for an analytic value
    std::vector<double> noise;           // scratch: the inner row's noise terms
    void clear() {
        row.clear();
        is_exact.clear();
    }
};

// Replaces out (its buffers reused). Adds to estimate, entry by entry in column order, each
// inner entry's systematic error and noise (the noise also to *noise when given); returns the number of entries the quadrature
// ratio rescaled.
std::uint64_t merge_row(const SparseRow& inner, std::span<const std::pair<std::uint32_t, double>> exact,
                        const SenderQuadrature& quadrature, const RowErrorModel& error, MergedRow& out,
                        double& estimate, RowNoise* noise = nullptr);

}  // namespace ffcube::accuracy
