// The side figures of a run's rows (RowSide: obstructed share, estimates, measure), noted by the
// consumer as the rows reach it, for what needs every row's at the end: the report's per-row
// figures, the sky view factors' obstructed shares, the patch table's estimates. Rows carry their
// figures themselves (through checkpoints and MPI chunks); the ledger only writes them down where
// they arrive, so it holds every row a run used, whichever process or checkpoint made it.
#pragma once

#include <cstdint>
#include <span>
#include <vector>

#include "ffcube/formfactor/sparse.hpp"

namespace ffcube {

class RowLedger {
public:
    explicit RowLedger(std::uint32_t n = 0) { resize(n); }
    // n rows, none noted (NaN estimates, measure −1, share 0).
    void resize(std::uint32_t n) {
        obstructed_.assign(n, 0.0);
        error_.assign(n, NAN);
        tolerance_error_.assign(n, NAN);
        measure_.assign(n, -1);
        any_ = false;
    }
    std::uint32_t size() const { return static_cast<std::uint32_t>(error_.size()); }
    // Row i's figures (i < size()); a later note of the same row replaces an earlier one.
    void note(std::uint32_t i, const RowSide& side) {
        obstructed_[i] = side.obstructed;
        error_[i] = side.error;
        tolerance_error_[i] = side.tolerance_error;
        measure_[i] = side.measure;
        any_ = any_ || side.measure >= 0 || !std::isnan(side.error);
    }
    // Whether any row noted so far had estimates or a measure (a run with the correction).
    bool any_figures() const { return any_; }
    std::span<const double> obstructed() const { return obstructed_; }
    std::span<const float> errors() const { return error_; }
    std::span<const float> tolerance_errors() const { return tolerance_error_; }
    std::span<const std::int8_t> measures() const { return measure_; }

private:
    std::vector<double> obstructed_;
    std::vector<float> error_, tolerance_error_;
    std::vector<std::int8_t> measure_;
    bool any_ = false;
};

}  // namespace ffcube
