// Files that other radiation solvers read (docs/outputs.md): NIST View3D's view-factor file, Elmer's
// ViewFactors.dat, a patch table that maps rows to geometry, and sky view factors. Every writer is
// atomic (atomic_file.hpp) and throws IoError when the file cannot be written.
#pragma once

#include <cstdint>
#include <filesystem>
#include <span>
#include <memory>
#include <span>
#include <string>
#include <vector>

#include "ffcube/core/progress.hpp"
#include "ffcube/formfactor/sparse.hpp"
#include "ffcube/io/matrix_sink.hpp"
#include "ffcube/scene/scene.hpp"

namespace ffcube {

// View3D's surfaces after combination: N areas, an N × N matrix F[n][m] (fraction of the energy
// leaving n that arrives at m; with emit = 1 Hottel's exchange factors), N emissivities.
struct View3dTable {
    std::vector<double> area;
    std::vector<std::vector<double>> F;
    std::vector<double> emissivity;
    int encl = 0;  // the header's flags, as View3D writes them
    int emit = 0;
};

// The header View3D 3.5 writes (savevf.c): "View3D 3.5 <format> <encl> <emit> <N>" blank-padded to
// 30 bytes; then "\n" (text: 31 bytes) or "\r\n" (binary: 32 bytes).
std::string view3d_header(int format, int encl, int emit, std::size_t n);

// Text (binary = false): the header, a line of the N areas ("%g"), N lines of N factors ("%.6f"),
// a line of N emissivities ("%.3f"). Binary: the 32-byte header, then float32 areas, rows, and
// emissivities, little-endian, nothing between them.
void write_view3d(const std::filesystem::path& path, const View3dTable& t, bool binary);

// The sparse text of View3D's forks (`out=2`; uDALES' View3D, savevf.c SaveF2): for every row n
// and column m (1-based) whose factor is at least 5e-7, a line "n m F" with F as "%.6f" of the
// double (not rounded to float first, as the fork prints it), rows in order and columns
// increasing in each; no header, areas or emissivities. Written row by row (memory: a 1 MiB
// buffer), atomically: nothing is in place until finish().
class View3dSparseWriter {
public:
    explicit View3dSparseWriter(const std::filesystem::path& path);
    ~View3dSparseWriter();
    View3dSparseWriter(const View3dSparseWriter&) = delete;
    View3dSparseWriter& operator=(const View3dSparseWriter&) = delete;
    // The next row (n = rows so far + 1): its columns (0-based, increasing) and factors.
    void append_row(std::span<const std::uint32_t> col, std::span<const double> val);
    void finish();
    std::uint64_t entries() const;  // lines written

private:
    struct Impl;
    std::unique_ptr<Impl> impl_;
};
inline constexpr double kView3dSparseThreshold = 5e-7;  // SaveF2's "FF >= 5E-7"

// View3D's file in the format of a .vs3's `out` key: 0 text, 1 binary, 2 sparse text (from the
// dense table, every row's non-zero columns).
void write_view3d(const std::filesystem::path& path, const View3dTable& t, int out);

// Elmer's ViewFactors.dat, as fem/src/ViewFactors.F90 writes it, for the patches as Elmer's
// radiation boundary elements: text: for every row i, a line with the count k of its non-zero
// factors, then k lines "i j F_ij" (1-based). Binary ("Viewfactor Binary Output", unformatted
// stream): int32 N, then per row int32 k and k pairs (int32 j, float64 F_ij). Little-endian.
// ElmerViewFactorsWriter writes it from the rows as they come (a MatrixSink: each row's lines depend
// on that row only, memory a 1 MiB buffer); write_elmer_view_factors is the same for a matrix.
class ElmerViewFactorsWriter final : public MatrixSink {
public:
    ElmerViewFactorsWriter(const std::filesystem::path& path, std::uint32_t n, bool binary);
    ~ElmerViewFactorsWriter() override;
    ElmerViewFactorsWriter(const ElmerViewFactorsWriter&) = delete;
    ElmerViewFactorsWriter& operator=(const ElmerViewFactorsWriter&) = delete;
    void append_row(RowView row) override;
    void finish() override;

private:
    struct Impl;
    std::unique_ptr<Impl> impl_;
};
void write_elmer_view_factors(const std::filesystem::path& path, const CsrMatrix& F, bool binary,
                              Progress* progress = nullptr);

// One line per patch, header "patch,object,area,cx,cy,cz,nx,ny,nz": the row/column index i
// (0-based, as in .ffm; Matrix Market's row i+1), its object's name, its area (scene units²), its
// centroid and its unit normal (front side).
// row_error: when given (one per patch), a last column error_estimate: the row's estimated error
// (docs/accuracy.md, "Accuracy by target"), empty where the row was not computed in this run.
void write_patch_table(const std::filesystem::path& path, const Scene& scene, std::span<const float> row_error = {});

// Sky view factors per patch: header "patch,object,area,sky_view_factor".
void write_patch_sky_csv(const std::filesystem::path& path, const Scene& scene, const std::vector<double>& svf);
// Per object: header "object,area,sky_view_factor" (area-weighted means).
void write_object_sky_csv(const std::filesystem::path& path, const std::vector<std::string>& names,
                          const std::vector<double>& area, const std::vector<double>& svf);

}  // namespace ffcube
