// Matrix Market output of a form-factor matrix, for scipy.io.mmread, MATLAB, Julia and friends.
#pragma once

#include <cstdint>
#include <filesystem>
#include <memory>

#include "ffcube/core/progress.hpp"
#include "ffcube/formfactor/sparse.hpp"
#include "ffcube/io/matrix_sink.hpp"

namespace ffcube {

// "%%MatrixMarket matrix coordinate real general" of an n × n matrix, written from its rows as
// they come (a MatrixSink): F[i][j] at row i+1, column j+1 (Matrix Market is 1-based), rows in
// order, columns increasing, values with 9 significant digits (every float reads back exactly).
// The header holds the number of entries, known only after the last row: the entry lines are
// spooled to an unlinked temporary file beside the output (memory: a 1 MiB buffer), and finish()
// writes the header, then copies the spooled lines after it. The disk holds the entry lines twice
// for that copy, which shows a progress bar when `progress`. Atomic (atomic_file.hpp); IoError when a file cannot be written.
class MtxWriter final : public MatrixSink {
public:
    MtxWriter(const std::filesystem::path& path, std::uint32_t n, bool progress = false);
    ~MtxWriter() override;
    MtxWriter(const MtxWriter&) = delete;
    MtxWriter& operator=(const MtxWriter&) = delete;

    void append_row(RowView row) override;
    void finish() override;
    std::uint64_t nnz() const;

private:
    struct Impl;
    std::unique_ptr<Impl> impl_;
};

// Writes F (every row filled) through MtxWriter: the same bytes as a streamed run's.
// progress, when given, is advanced by one per row.
void write_mtx(const std::filesystem::path& path, const CsrMatrix& F, Progress* progress = nullptr);

}  // namespace ffcube
