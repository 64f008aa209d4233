// Row i of a matrix together with its column i, in row order, for a matrix streamed to a file and
// never held in memory (the reciprocity check and --enforce of `ffcube formfactors -o F.ffm`;
// docs/robustness.md, "Memory").
//
// The columns are cut into bands whose entries fit a memory budget. One pass over the matrix
// writes every entry F_ij into the scratch file of the band of column j (a run per row and band:
// u32 row, u32 count, the columns, the float values), then a second pass reads the rows again and,
// on entering a band, loads that band's file into memory, sorted by column (rows stay in
// increasing order, as they were written): two passes over the matrix, whatever the budget (more
// only when there are more than kMaxOpenBands bands: one pass per kMaxOpenBands). One band
// (everything fits) needs no scratch file.
#pragma once

#include <cstdint>
#include <filesystem>
#include <functional>
#include <memory>
#include <span>
#include <vector>

#include "ffcube/core/progress.hpp"
#include "ffcube/formfactor/checks.hpp"

namespace ffcube {

// A fresh directory for scratch files next to an output file ("DIR/.NAME.scratch.PID.K"),
// removed with everything in it when destroyed: on success and on error (an exception unwinds
// through it). IoError naming the directory when it cannot be created.
class ScratchDir {
public:
    explicit ScratchDir(const std::filesystem::path& next_to);
    ~ScratchDir();
    ScratchDir(const ScratchDir&) = delete;
    ScratchDir& operator=(const ScratchDir&) = delete;
    const std::filesystem::path& path() const { return path_; }

private:
    std::filesystem::path path_;
};

inline constexpr std::size_t kMaxOpenBands = 64;  // scratch files written by one pass

struct TransposePlan {
    std::vector<std::uint32_t> bands;  // first column of each band, then n
    std::size_t passes = 0;            // passes over the matrix
    // One band, and the rows f is given fit beside it: one pass keeps both (passes 1).
    bool keep_rows = false;
    std::size_t band_count() const { return bands.empty() ? 0 : bands.size() - 1; }
};
// Bands of consecutive columns holding at most budget_entries entries each (at least one column).
// Memory while a band is loaded: 8 bytes per entry (u32 row, float value) and 16 per column; while
// spilling, a 64 KiB buffer per open file (at most kMaxOpenBands).
// kept_row_entries: the entries of the rows f is given (ColumnPart::below_diagonal: those right of
// the diagonal); when they and the one band fit in budget_entries together, one pass over the
// matrix keeps both (plan.keep_rows) instead of reading it twice.
TransposePlan plan_transpose(std::span<const std::uint32_t> col_counts, std::uint64_t budget_entries,
                             std::uint64_t kept_row_entries = UINT64_MAX);

struct TransposeFigures {
    std::size_t passes = 0;            // passes made over the matrix (plan.passes)
    std::uint64_t scratch_bytes = 0;   // written to scratch files
};
// part: every F_ki of column i, or those below the diagonal (formfactor/checks.hpp ColumnPart).
// Calls f with every row i of the matrix `pass` goes over and its column i, in row order. With
// ColumnPart::below_diagonal, f's row is the row's entries right of the diagonal (j > i) and the
// column F_ki for k > i: each pair (i, k) once, at row min(i, k).
// col_counts: the entries per column (RowStreamChecks::col_counts, or lower_col_counts for
// ColumnPart::below_diagonal), as the plan was made from.
// Scratch files go to scratch_dir and are removed as soon as read. progress, when given, is
// advanced by one per row of each pass. IoError naming the scratch file when writing or reading it
// fails (disk full); InternalError when a pass gives other rows than the first.
TransposeFigures for_each_row_and_column(const RowPass& pass, std::span<const std::uint32_t> col_counts,
                                         const TransposePlan& plan, const std::filesystem::path& scratch_dir,
                                         const RowAndColumnFn& f, Progress* progress = nullptr,
                                         ColumnPart part = ColumnPart::all);

// Rows of (u32 column, double value) written once and read back in order any number of times
// (--enforce closure's G, one pass per iteration): held in memory while they take at most
// memory_bytes (12 bytes per entry, 8 per row), then moved to the scratch file at `path` and read
// from it. IoError naming the file when writing or reading it fails.
class ScratchRows {
public:
    ScratchRows(std::filesystem::path path, std::uint64_t memory_bytes);
    ~ScratchRows();
    ScratchRows(const ScratchRows&) = delete;
    ScratchRows& operator=(const ScratchRows&) = delete;
    void append(std::span<const std::uint32_t> col, std::span<const double> val);
    // Every row appended, in order, as (row index, columns, values).
    void for_each(const std::function<void(std::uint32_t, std::span<const std::uint32_t>, std::span<const double>)>& f);
    bool on_disk() const;
    std::uint64_t bytes() const;  // written to the scratch file

private:
    struct Impl;
    std::unique_ptr<Impl> impl_;
};

}  // namespace ffcube
