// The outputs of `ffcube formfactors` that other tools read (docs/outputs.md): sky view factors,
// View3D's view-factor file, Elmer's ViewFactors.dat, the patch table; and the View3D control
// keys of a .vs3 scene that change how the matrix is made (encl). Composition only: the numbers
// come from formfactor/sky.hpp and solver/exchange.hpp, the bytes from io/solver_files.hpp.
#pragma once

#include <filesystem>
#include <memory>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "ffcube/formfactor/checks.hpp"
#include "ffcube/formfactor/sparse.hpp"
#include "ffcube/io/report.hpp"
#include "ffcube/io/solver_files.hpp"
#include "ffcube/pipeline/options.hpp"
#include "ffcube/scene/scene.hpp"

namespace ffcube {

enum class SkyBy { Patch, Object };
enum class FileFormat { Auto, Text, Binary };

struct SurfaceOutputOptions {
    std::string sky;                  // --sky S.csv
    SkyBy sky_by = SkyBy::Patch;      // --sky-by patch|object
    std::string view3d;               // --view3d F: View3D's view-factor file (one surface per object)
    FileFormat view3d_format = FileFormat::Auto;  // --view3d-format: auto = the .vs3's `out`, else text
    std::string elmer;                // --elmer ViewFactors.dat (one row per patch)
    FileFormat elmer_format = FileFormat::Auto;   // --elmer-format: auto = text
    std::string patch_table;          // --patch-table P.csv
    std::string fields;               // --fields OUT.vtu: per-patch sky view factor and row sum on the mesh (io/vtu.hpp)
};

SkyBy parse_sky_by(std::string_view text);            // patch | object
FileFormat parse_file_format(std::string_view text);  // auto | text | binary

// A .vs3 scene's encl=1 asks for rows that conserve energy: --enforce closure, unless the command
// line chose an --enforce mode (which wins; the report says so). Recorded under "view3d" in the
// report with the title and every ignored control key.
// The keys only `ffcube view3d` acts on (View3dControls::row, col, max_distance): other commands
// (drop_in = false) warn, naming the line, that they ignore them; `ffcube view3d` (drop_in = true)
// refuses row and col (View3D's one-row debugging run) naming the line, and applies maxD with
// View3dCutoff.
void apply_view3d_controls(const Scene& scene, RowOptions& rows, Report& report, bool drop_in = false);

// The forks' cut-off distance (a .vs3's maxD; uDALES' View3D, view3d.c: a pair of surfaces whose
// centroids lie more than maxD apart gets no factor), row by row as the rows come: row i with every
// entry F_ij of a patch j whose centroid lies farther than max_distance from i's removed; what
// they carried counts as sky. With --no-subdivide each patch is one View3D surface (the loader
// refuses maxD with subsurfaces). max_distance <= 0: rows unchanged.
class View3dCutoff {
public:
    View3dCutoff(const Scene& scene, double max_distance) : scene_(scene), max_(max_distance) {}
    // Valid until the next call.
    RowView operator()(std::uint32_t i, RowView row);

private:
    const Scene& scene_;
    double max_;
    std::vector<std::uint32_t> col_;
    std::vector<float> val_;
};

// View3D's file of the finished matrix F in format `out` (0 text, 1 binary, 2 sparse text): the
// table of view3d_table. With out = 2, no masking surfaces and emit = 0, the object rows are
// summed one object at a time straight from F (memory: the number of surfaces, not its square), in
// the order and with the operations of object_form_factors: the same bytes as from the table.
// Reports view3d.written, view3d.format, view3d.surfaces (and view3d.entries for out = 2).
void write_view3d_output(const std::filesystem::path& path, const CsrMatrix& F, const Scene& scene, int out,
                         Report& report);

// The View3D table of F: one surface per object (a .vs3's S surfaces, cmb groups as one, named
// by the group's first surface), in object order: areas, object form factors (F to a group is the
// sum over its parts, F from it the area-weighted mean), emissivities ε = 1 − Kd (area-weighted,
// mean of RGB; a .vs3 gives Kd = 1 − ε). With the scene's emit=1, Hottel's exchange factors.
View3dTable view3d_table(const CsrMatrix& F, const Scene& scene);
// The same from the object form factors (object_form_factors, or RowStreamChecks::object_factors
// of the streamed rows: the same numbers).
View3dTable view3d_table(std::vector<std::vector<double>> object_factors, const Scene& scene);

// Only what needs each row's sum and the scene: the sky statistics, --sky and --patch-table (what
// `solve --sky` writes; write_surface_outputs below calls it too). `obstructed` (empty, or per row
// the share obstruction-only surfaces intercepted) is taken off the sky view factors.
void write_sky_outputs(const SurfaceOutputOptions& o, std::span<const double> row_sums, const Scene& scene, Report& report,
                       std::span<const double> obstructed = {}, std::span<const float> row_error = {});
// Elmer's file is written from the rows as they come, by the sink this gives (null when --elmer is
// not asked) and the caller feeds and finishes; the rest (sky statistics into the report always,
// then every file asked for) comes from each row's sum and from `checks` (the finished rows'
// RowStreamChecks: View3D's object factors).
std::unique_ptr<MatrixSink> open_elmer_sink(const SurfaceOutputOptions& o, std::uint32_t n);
void write_surface_outputs(const SurfaceOutputOptions& o, std::span<const double> row_sums,
                           const RowStreamChecks& checks, const Scene& scene, Report& report,
                           std::span<const double> obstructed = {}, std::span<const float> row_error = {});

}  // namespace ffcube
