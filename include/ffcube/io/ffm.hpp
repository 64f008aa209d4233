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
#include <string>
#include <vector>

#include "ffcube/core/progress.hpp"
#include "ffcube/formfactor/sparse.hpp"
#include "ffcube/scene/scene.hpp"

namespace ffcube {

inline constexpr std::uint32_t kFfmVersion = 1;

// How the rows were made. Must not hold run-dependent data (see above).
struct FfmMetadata {
    std::string method;            // "hemicube", "raycast", ...
    std::uint32_t resolution = 0;  // hemicube top-face pixels; 0 when the method is not a hemicube
    // Free-form settings that shaped the rows beyond method and resolution (e.g. "rotate=1").
    std::string settings;

    bool operator==(const FfmMetadata&) const = default;
};

// A .ffm file as read and validated by read_ffm().
struct FfmFile {
    std::string source;  // the path it was read from, for messages
    FfmMetadata meta;
    std::uint64_t fingerprint = 0;          // Scene::fingerprint of the scene the rows were computed for
    double max_patch_edge = 0.0;            // MeshStats::max_patch_edge of that scene, scene units
    std::string meshing;                    // MeshStats::how of that scene
    std::vector<double> areas;              // patch areas, scene units², each finite and > 0
    std::vector<std::uint32_t> objects;     // object index of each patch, < object_names.size()
    std::vector<std::string> object_names;  // as in the OBJ
    CsrMatrix matrix;                       // n × n, every row filled
};

// Writes F (every row filled, F.size() == scene.size()) with the scene's patch areas, objects,
// object names, fingerprint and meshing, atomically (see atomic_file.hpp). Throws IoError when
// the file cannot be written.
// progress, when given, is advanced by the bytes written (about ffm_payload_bytes(F) in all).
void write_ffm(const std::filesystem::path& path, const CsrMatrix& F, const Scene& scene, const FfmMetadata& meta,
               Progress* progress = nullptr);
std::uint64_t ffm_payload_bytes(const CsrMatrix& F);

// Reads and validates a .ffm file. Nothing in it is trusted before it is checked: magic, version,
// the file size implied by the header (checked before anything is allocated), the checksum, then
// the structure (row_ptr monotone and ending at nnz, columns < n and strictly increasing in each
// row, values finite and in [0, 1+1e-3], areas finite and > 0, object indices in range).
// Throws InputError "PATH: <what is wrong>" for a file that cannot be opened or is not a valid
// .ffm (e.g. "F.ffm: truncated: expected 123456 bytes, found 1000"), IoError when reading fails.
FfmFile read_ffm(const std::filesystem::path& path);

// Throws InputError unless the file was computed for this scene and meshing: same fingerprint,
// and (as a guard against a fingerprint collision) the same patch count.
void check_ffm_matches(const FfmFile& file, const Scene& scene);

}  // namespace ffcube
