// A file written from a stream of rows: rows 0..n-1, each once, in order, as RowView (float
// values, what CsrMatrix holds), the file made at finish(). The streamed `ffcube formfactors`
// feeds every output it writes (.ffm, .mtx, Elmer's ViewFactors.dat) through this interface while
// the rows are computed, so memory does not grow with the number of entries; an MPI rank 0 that
// receives the ranks' rows in order can feed the same sinks. Atomic like every output
// (atomic_file.hpp): destroyed before finish(), nothing is left under the file's name.
#pragma once

#include <utility>

#include "ffcube/formfactor/sparse.hpp"

namespace ffcube {

// (Not formfactor/row_provider.hpp's RowSink, the callback a RowProvider delivers rows to.)
class MatrixSink {
public:
    virtual ~MatrixSink() = default;
    // The next row (rows_written()): columns strictly increasing and < n.
    virtual void append_row(RowView row) = 0;
    // Needs every row; writes what is left and renames the file into place. IoError when a write
    // fails (disk full).
    virtual void finish() = 0;
};

// The rows held in memory, as a CsrMatrix: one more sink beside the files (Python's form_factors,
// `ffcube view3d`). matrix() is complete after finish().
class CsrMatrixSink final : public MatrixSink {
public:
    explicit CsrMatrixSink(std::uint32_t n) : matrix_(n) {}
    void append_row(RowView row) override { matrix_.append_row(row.col, row.val); }
    void finish() override;
    const CsrMatrix& matrix() const { return matrix_; }
    CsrMatrix take() { return std::move(matrix_); }

private:
    CsrMatrix matrix_;
};

}  // namespace ffcube
