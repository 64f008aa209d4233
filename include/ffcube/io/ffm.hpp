// .ffm: ffcube's binary sparse form-factor matrix (layout in docs/ffm-format.md).
// Little-endian, versioned, 8-byte aligned sections, a trailing checksum. It stores, besides the
// CSR rows, what is needed to refuse it for the wrong scene (the scene fingerprint, patch areas,
// the object of each patch) and how the rows were made. It holds no run-dependent data (no
// time, thread count or host), so the same command writes byte-identical files.
//
// Matrix convention as everywhere in ffcube: F[i][j] = fraction of the energy leaving patch i
// that arrives at patch j; row i holds the nonzero F[i][j] with j strictly increasing.
#pragma once

#include <cstdint>
#include <filesystem>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "ffcube/core/progress.hpp"
#include "ffcube/formfactor/sparse.hpp"
#include "ffcube/io/matrix_sink.hpp"
#include "ffcube/scene/scene.hpp"

namespace ffcube {

// The version write_ffm and FfmWriter write: 2 (compact: delta-coded columns, zstd row blocks,
// a checksum per block). read_ffm reads 1 and 2.
inline constexpr std::uint32_t kFfmVersion = 2;

// How the rows were made. Must not hold run-dependent data (see above).
struct FfmMetadata {
    std::string method;            // "hemicube", "raycast", ...
    std::uint32_t resolution = 0;  // hemicube top-face pixels; 0 when the method is not a hemicube
    // Free-form settings that shaped the rows beyond method and resolution (e.g. "rotate=1").
    std::string settings;

    bool operator==(const FfmMetadata&) const = default;
};

// Everything in a .ffm file but the matrix rows.
struct FfmHead {
    std::string source;  // the path it was read from, for messages
    std::uint32_t version = 0;
    std::uint32_t n = 0;                    // patches: rows and columns
    FfmMetadata meta;
    std::uint64_t fingerprint = 0;          // Scene::fingerprint of the scene the rows were computed for
    double max_patch_edge = 0.0;            // MeshStats::max_patch_edge of that scene, scene units
    std::string meshing;                    // MeshStats::how of that scene
    std::vector<double> areas;              // patch areas, scene units², each finite and > 0
    std::vector<std::uint32_t> objects;     // object index of each patch, < object_names.size()
    std::vector<std::string> object_names;  // as in the OBJ
};

// A .ffm file as read and validated by read_ffm().
struct FfmFile : FfmHead {
    CsrMatrix matrix;  // n × n, every row filled
};

// Writes F (every row filled, F.size() == scene.size()) with the scene's patch areas, objects,
// object names, fingerprint and meshing, atomically (see atomic_file.hpp). Throws IoError when
// the file cannot be written.
// progress, when given, is advanced by the bytes written (about ffm_payload_bytes(F) in all).
// Version 2 (the default) advances progress by one per row, version 1 by the bytes written
// (about ffm_payload_bytes(F) in all); ffm_progress_total gives the total for either.
void write_ffm(const std::filesystem::path& path, const CsrMatrix& F, const Scene& scene, const FfmMetadata& meta,
               Progress* progress = nullptr, std::uint32_t version = kFfmVersion);
std::uint64_t ffm_payload_bytes(const CsrMatrix& F);
std::uint64_t ffm_progress_total(const CsrMatrix& F, std::uint32_t version = kFfmVersion);

// Version 2, written as the rows come (rows in order 0..n-1), in memory bounded by one block of
// rows: a row is coded into the current block, and a block full (about block_bytes of coded
// rows) is compressed, checksummed and written. Atomic like write_ffm: the file appears under its
// name only at finish(); destroyed before, nothing is left behind. Values are stored as the float
// CsrMatrix keeps (a SparseRow's double is rounded as CsrMatrix::append_row rounds it), so a
// streamed matrix and write_ffm of the same rows give byte-identical files.
struct FfmWriterOptions {
    std::uint32_t block_bytes = 1u << 20;  // coded bytes per block (before compression)
    int zstd_level = 3;
};
class FfmWriter final : public MatrixSink {
public:
    FfmWriter(const std::filesystem::path& path, const Scene& scene, const FfmMetadata& meta,
              FfmWriterOptions options = {});
    ~FfmWriter();
    FfmWriter(const FfmWriter&) = delete;
    FfmWriter& operator=(const FfmWriter&) = delete;

    // Row rows_written(): columns strictly increasing and < n, values finite in [0, 1.001]
    // (InternalError otherwise: a file the reader would refuse is never written).
    void append_row(const SparseRow& row);
    void append_row(RowView row) override;
    std::uint32_t rows_written() const;
    std::uint64_t nnz() const;
    std::uint64_t bytes_written() const;
    // Needs every row; writes the last block and the trailer, then renames the file into place.
    // Throws IoError when a write fails (disk full).
    void finish() override;

private:
    struct Impl;
    std::unique_ptr<Impl> impl_;
};

// One block of rows of a version-2 file, validated.
struct FfmBlock {
    std::uint32_t first_row = 0, rows = 0;
    std::vector<std::uint64_t> row_ptr;  // rows + 1 offsets into col/val, from 0
    std::vector<std::uint32_t> col;
    std::vector<float> val;
    RowView row(std::uint32_t k) const;  // k < rows: row first_row + k
};

// Reads a version-2 file block by block, in memory bounded by one block (and the head: areas
// and objects). The head is validated on opening (as read_ffm does); each block is checked
// (checksum, then its structure) when next() reaches it, and the trailer (row and entry counts,
// the checksum over every block's) after the last: a damaged file throws InputError, naming the
// block and its rows ("F.ffm: block 17 (rows 4352..4607): checksum mismatch").
class FfmReader {
public:
    explicit FfmReader(const std::filesystem::path& path);
    ~FfmReader();
    FfmReader(FfmReader&&) noexcept;
    const FfmHead& head() const;
    // The next block; false after the last one (once the trailer has been checked).
    bool next(FfmBlock& block);
    void rewind();
    // Every row in order (rewinds first).
    void for_each_row(const std::function<void(std::uint32_t, RowView)>& f);

private:
    struct Impl;
    std::unique_ptr<Impl> impl_;
};

// Reads and validates a .ffm file of either version. Nothing in it is trusted before it is checked: magic, version,
// the file size implied by the header (checked before anything is allocated), the checksum, then
// the structure (row_ptr monotone and ending at nnz, columns < n and strictly increasing in each
// row, values finite and in [0, 1+1e-3], areas finite and > 0, object indices in range).
// Throws InputError "PATH: <what is wrong>" for a file that cannot be opened or is not a valid
// .ffm (e.g. "F.ffm: truncated: expected 123456 bytes, found 1000"), IoError when reading fails.
FfmFile read_ffm(const std::filesystem::path& path);

// Throws InputError unless the file was computed for this scene and meshing: same fingerprint,
// and (as a guard against a fingerprint collision) the same patch count.
void check_ffm_matches(const FfmFile& file, const Scene& scene);
// The same from a file's head (FfmReader: the rows are not read).
void check_ffm_matches(const FfmHead& head, const Scene& scene);

}  // namespace ffcube
