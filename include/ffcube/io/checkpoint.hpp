// A checkpoint of a form-factor precomputation: finished rows are streamed to a directory as
// they come, so that a run killed at any moment (kill -9, out of memory, a lost node) can be
// resumed without computing those rows again (layout and guarantees in docs/robustness.md).
//
// DIR/manifest.txt  what the rows depend on: scene fingerprint, patch count, meshing, method,
//                   resolution and settings (written atomically when the checkpoint is created).
// DIR/rows.log      an append-only log of records, one per row, each with its own checksum:
//                     u32 magic "FFCR", u32 row, u32 nnz, u32 flags,
//                     u32 col[nnz], f32 val[nnz], [f64 obstructed],
//                     [f32 error, f32 tolerance_error, i32 measure, u32 0], u64 checksum64 of
//                     everything before it
//                   (little-endian; every record is a multiple of 8 bytes). Values are stored as
//                   the float the CsrMatrix keeps, so a matrix assembled from the log is
//                   bit-identical to one built from the rows directly. flags is 1 in every record
//                   of a checkpoint whose manifest says "obstructions 1" (a scene with
//                   obstruction-only surfaces, Scene::drawn): the record then holds the row's
//                   obstructed share (RowSide::obstructed, the double's bits); flag 2 is set in
//                   every record of a format 3 checkpoint: the record then holds the row's
//                   estimates and measure (RowSide: error, tolerance_error, measure), so a
//                   resumed run's rows come back with their figures.
// Format 2 (the manifest's first line "ffcube-checkpoint 2") added the flags and the
// "obstructions" line, format 3 the figures (flag 2); format 1 and 2 checkpoints (without
// obstructions, resp. figures) are still read and continued in their own format.
#pragma once

#include <cstdint>
#include <filesystem>
#include <functional>
#include <span>
#include <string>
#include <vector>

#include "ffcube/formfactor/sparse.hpp"
#include "ffcube/io/ffm.hpp"

namespace ffcube {

// Everything a row depends on. Two runs with equal manifests compute identical rows.
struct CheckpointManifest {
    std::uint64_t fingerprint = 0;  // Scene::fingerprint
    std::uint32_t patches = 0;      // Scene::size()
    std::string meshing;            // MeshStats::how
    double max_patch_edge = 0.0;    // MeshStats::max_patch_edge
    FfmMetadata meta;               // method, resolution, settings (rotation, seed, ...)
    // The scene has obstruction-only surfaces: every record holds its row's obstructed share.
    bool obstructions = false;

    bool operator==(const CheckpointManifest&) const = default;
};

class RowCheckpoint {
public:
    // Starts a new checkpoint in dir (created when missing; its parent must exist). Throws
    // InputError when dir already holds a checkpoint (finished work is never overwritten: resume
    // it or remove it) or is not a directory; IoError when the files cannot be created.
    static RowCheckpoint create(const std::filesystem::path& dir, const CheckpointManifest& manifest);

    // Opens dir's checkpoint to continue it. Throws InputError when dir holds no checkpoint, or
    // when its manifest differs from 'manifest' (the message names each differing setting with
    // both values). Reads the log and keeps every record that is complete and whose checksum and
    // content (row < patches, columns increasing and < patches, values finite in [0, 1.001]) hold:
    //  - a torn last record (the run was killed during a write) is cut off, with a note in
    //    warnings();
    //  - a corrupted record (bad magic, checksum or content) is dropped with everything after it
    //    (the framing after it cannot be trusted), with a warning naming its offset.
    // The log is truncated to the last kept record before new rows are appended.
    static RowCheckpoint resume(const std::filesystem::path& dir, const CheckpointManifest& manifest);

    RowCheckpoint(RowCheckpoint&&) noexcept;
    RowCheckpoint& operator=(RowCheckpoint&&) noexcept;
    ~RowCheckpoint();  // syncs (best effort) and closes the log

    std::uint32_t size() const { return static_cast<std::uint32_t>(offsets_.size()); }
    bool has(std::uint32_t i) const { return offsets_[i] != kMissing; }
    std::uint32_t rows_stored() const { return stored_; }
    std::vector<std::uint32_t> missing() const;  // rows not in the log, ascending
    const std::vector<std::string>& warnings() const { return warnings_; }
    // Appends row i (i < size(), not yet stored; columns strictly increasing) with one write(2):
    // once it returns the row survives the process being killed. The log is fsync'ed at most
    // once a second here (an fsync per row would dominate small rows) and by sync(), so a power
    // loss costs at most the last second of rows. Throws IoError when the write fails.
    // The row's side figures go with it: its obstructed share (stored when the manifest has
    // obstructions, else required to be 0) and, in format 3, its estimates and measure.
    void append(std::uint32_t i, const SparseRow& row);
    // fsync's the log. Throws IoError on failure.
    void sync();

    // The whole matrix, rows in order (entries only), read back from the log (each record's checksum checked
    // again). Requires missing().empty(). Throws InputError when a record changed on disk since
    // it was read, IoError when reading fails.
    CsrMatrix assemble() const;
    // Rows [first, last) (each stored), read back like assemble() and appended to the arrays:
    // nnz[k] entries of row first + k, their columns and values, and its side figures. How one
    // MPI rank's shard gives back its block of rows (src/mpi).
    void read_rows(std::uint32_t first, std::uint32_t last, std::vector<std::uint32_t>& nnz,
                   std::vector<std::uint32_t>& col, std::vector<float>& val, std::vector<RowSide>& side) const;

    // Every row in order with its side figures, read back from the log one record at a time
    // (memory: one row), each record's checksum checked again; what assemble() is made of. Same
    // requirements and errors.
    void for_each_row(const std::function<void(std::uint32_t, RowView)>& f) const;

    std::string log_path() const;

private:
    static constexpr std::uint64_t kMissing = ~std::uint64_t{0};
    RowCheckpoint(std::filesystem::path dir, std::uint32_t n, bool obstructions, bool figures);
    std::uint64_t record_size(std::uint32_t nnz) const;
    void maybe_sync();

    std::filesystem::path dir_;
    int fd_ = -1;
    std::uint64_t end_ = 0;               // bytes of the log that hold kept records
    std::vector<std::uint64_t> offsets_;  // record offset of each row, or kMissing
    std::uint32_t stored_ = 0;
    std::vector<std::string> warnings_;
    double last_sync_ = 0.0;              // steady-clock seconds
    std::vector<unsigned char> buffer_;   // one record, reused
    std::uint32_t flags_ = 0;             // every record's flags: 1 with obstructions, 2 with figures
};

}  // namespace ffcube
