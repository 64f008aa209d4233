#include "cli/surface_options.hpp"

#include "cli/common.hpp"
#include "cli/expert.hpp"
#include "ffcube/io/fields.hpp"

namespace ffcube::cli {

void add_sky_options(CLI::App& app, SurfaceOutputOptions& o) {
    app.add_option("--sky", o.sky, "write sky view factors 1 - sum_j F_ij as CSV (per patch, or per object with --sky-by)");
    app.add_option_function<std::string>(
           "--sky-by", [&o](const std::string& w) { o.sky_by = parse_sky_by(w); },
           "rows of --sky: patch (patch,object,area,sky_view_factor) or object (object,area,sky_view_factor)")
        ->check(CLI::IsMember({"patch", "object"}))
        ->default_str("patch");
}

void add_surface_output_options(CLI::App& app, SurfaceOutputOptions& o) {
    add_sky_options(app, o);
    app.add_option("--view3d", o.view3d, "write View3D's view-factor file (one surface per object, cmb groups combined)");
    expert(app.add_option_function<std::string>(
           "--view3d-format", [&o](const std::string& w) { o.view3d_format = parse_file_format(w); },
           "auto (the .vs3's out key, else text), text or binary")
        ->check(CLI::IsMember({"auto", "text", "binary"}))
        ->default_str("auto"));
    expert(app.add_option("--elmer", o.elmer, "write Elmer's ViewFactors.dat (one row per patch)"));
    expert(app.add_option_function<std::string>(
           "--elmer-format", [&o](const std::string& w) { o.elmer_format = parse_file_format(w); },
           "auto (= text), text or binary (Elmer's 'Viewfactor Binary Output')")
        ->check(CLI::IsMember({"auto", "text", "binary"}))
        ->default_str("auto"));
    app.add_option("--patch-table", o.patch_table,
                   "write the patch table as CSV (patch,object,area,cx,cy,cz,nx,ny,nz; element_id for a mesh read through Gmsh; error_estimate, each row's, with the near-field correction)");
    expert(app.add_option("--fields", o.fields,
                          "write the meshed scene with per-patch fields (sky view factor, row sum, element id): OUT.vtu "
                          "for ParaView, or OUT.msh, a Gmsh model with views (docs/fe-meshes.md)"));
}

void check_surface_output_paths(const SurfaceOutputOptions& o) {
    check_output_path("--sky", o.sky);
    check_output_path("--view3d", o.view3d);
    check_output_path("--elmer", o.elmer);
    check_output_path("--patch-table", o.patch_table);
    check_output_path("--fields", o.fields);
    check_fields_path("--fields", o.fields);
}

}  // namespace ffcube::cli
