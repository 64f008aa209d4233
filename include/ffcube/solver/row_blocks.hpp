// A gathering solve (Jacobi, Gauss–Seidel) split over processes: each owns a block of rows
// [first, last), asks the row provider for those rows only, sweeps them, and after every sweep
// shares its block of B with the others. The solver layer knows nothing of how: src/mpi
// implements this over MPI (docs/scaling.md); tests can implement it in one process.
#pragma once

#include <cstdint>
#include <span>

namespace ffcube {

class RowBlocks {
public:
    virtual ~RowBlocks() = default;
    virtual std::uint32_t first() const = 0;
    virtual std::uint32_t last() const = 0;
    // x has every row; on entry this block's rows hold its newest values, on return every row
    // holds its owner's newest values.
    virtual void share(std::span<double> x) = 0;
    // Element-wise sum (max) of v over all blocks, in place; the same bits on every block.
    virtual void sum(std::span<double> v) = 0;
    virtual void max(std::span<double> v) = 0;
};

}  // namespace ffcube
