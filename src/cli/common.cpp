#include "cli/common.hpp"

#include <fmt/format.h>

#include <filesystem>
#include <vector>

#include "cli/expert.hpp"
#include "ffcube/core/error.hpp"
#include "ffcube/io/csv.hpp"
#include "ffcube/solver/solver.hpp"

namespace ffcube::cli {

namespace {

// A word option: CLI11 checks the word against the accepted ones (refused at parse time with the
// list, exit 2), then the library's parser turns it into the enum (pipeline/options.hpp), once.
template <typename E>
CLI::Option* add_word_option(CLI::App& app, const std::string& name, E& target, E (*parse)(std::string_view),
                             std::vector<std::string> accepted, const std::string& help, const std::string& default_word) {
    return app
        .add_option_function<std::string>(
            name, [&target, parse](const std::string& word) { target = parse(word); }, help)
        ->check(CLI::IsMember(std::move(accepted)))
        ->default_str(default_word);
}

}  // namespace

void add_scene_options(CLI::App& app, SceneFlags& o) {
    app.add_option("scene", o.scene.path,
                   "scene file: OBJ, STL, View3D .vs3, PLY, glTF (.gltf/.glb) or another format assimp reads, a mesh "
                   "(.msh, .unv, .bdf, .vtk) or CAD (.step, .iges) through Gmsh (default: the built-in Cornell box)");
    auto* edge =
        app.add_option("--max-patch-edge", o.scene.max_patch_edge, "split faces so that no patch edge exceeds L (scene units)")
            ->check(CLI::PositiveNumber);
    auto* patches = app.add_option("--patches", o.scene.patches, "mesh to about N patches (default: 2000)")
                        ->check(CLI::PositiveNumber)
                        ->excludes(edge);
    expert(add_word_option(app, "--format", o.scene.format, parse_scene_format,
                    {"auto", "obj", "stl", "vs3", "ply", "gltf", "glb", "assimp", "msh", "unv", "bdf", "nas", "vtk", "step", "stp",
                     "iges", "igs", "gmsh"},
                    "scene format: auto (by the extension), obj, stl, vs3, or ply, gltf, glb, assimp (through assimp), or "
                    "msh, unv, bdf, nas, vtk, step, stp, iges, igs, gmsh (through Gmsh)", "auto"));
    app.add_option("--materials", o.scene.materials,
                   "CSV of Kd and Ke per object (object,kd_r,kd_g,kd_b,ke_r,ke_g,ke_b) for formats without materials; "
                   "a triple left empty keeps the file's (docs/scene-format.md)")
        ->check(CLI::ExistingFile);
    app.add_flag_function(
           "--no-subdivide", [&o](std::int64_t) { o.scene.subdivide = false; },
           "every input face is one patch (triangles and convex planar quads only)")
        ->excludes(edge)
        ->excludes(patches);
    expert(add_word_option(app, "--contact-cuts", o.scene.contact_cuts, parse_contact_cuts, {"auto", "on", "off"},
                    "cut faces along the polygons where other objects stand on them, before meshing (auto: on "
                    "unless --no-subdivide; docs/adaptive.md)",
                    "auto"));
    expert(app.add_flag_function(
        "--no-contact-cuts", [&o](std::int64_t) { o.scene.contact_cuts = ContactCuts::Off; }, "the same as --contact-cuts off"));
    expert(app.add_option_function<std::string>(
                  "--objects-by",
                  [&o](const std::string& w) {
                      if (w == "group" || w == "entity" || w == "element")
                          o.scene.fe_objects_by = w == "group" ? FeObjectsBy::group : w == "entity" ? FeObjectsBy::entity : FeObjectsBy::element;
                      else if (w.starts_with("field:"))
                          o.scene.fe_field = w.substr(6);
                      else
                          o.scene.objects_by = parse_objects_by(w);
                  },
                  "what names objects: in an OBJ auto (default: o, else g, else the material), o, g or material; in a "
                  "mesh read through Gmsh group (default: physical groups), entity or element; in a legacy .vtk "
                  "field:NAME, its integer cell array NAME (docs/fe-meshes.md)")
               ->check([](const std::string& w) -> std::string {
                   for (const char* k : {"auto", "o", "g", "material", "group", "entity", "element"})
                       if (w == k) return "";
                   if (w.starts_with("field:") && w.size() > 6) return "";
                   return "must be auto, o, g, material, group, entity, element or field:NAME, not '" + w + "'";
               })
               ->default_str("auto"));
    expert(app.add_option("--flip", o.scene.flip,
                          "reverse the faces of these groups (objects) of a mesh read through Gmsh: --flip a,b (docs/fe-meshes.md)")
               ->delimiter(','));
    app.add_flag("-q,--quiet", o.quiet, "no progress or summary on stderr (warnings and errors still)");
}

void add_adaptive_options(CLI::App& app, AdaptiveFlags& o) {
    o.target_error = app.add_option("--target-error", o.options.target_error,
                                    "adaptive meshing: refine until every object's estimated relative error is below E")
                         ->default_val(o.options.target_error);
    o.max_elements = app.add_option("--max-elements", o.options.max_elements, "adaptive meshing: most elements (patches after refinement)")
                         ->default_val(o.options.max_elements);
}

void prepare_adaptive(const AdaptiveFlags& o, SceneOptions& scene) {
    if (!o.on()) return;
    validate(o.options);
    if (scene.patches == 0 && scene.max_patch_edge == 0.0 && scene.subdivide)
        scene.patches = kAdaptiveStartPatches;  // the coarse start (docs/adaptive.md)
}

void add_row_options(CLI::App& app, RowOptions& o, RowTolerance tolerance) {
    o.method_auto = true;  // --method's default
    o.tolerance = kDefaultTolerance;
    CLI::Option* target = app.add_option_function<double>(
           tolerance == RowTolerance::main ? "--tolerance" : "--row-tolerance",
           [&o](double e) { o.tolerance = e, o.tolerance_given = true; },
           "accuracy target E: the largest error a row may keep in any F entry and in its sum (the sky view factor); "
           "ray-cast rows are refined until their estimate meets it, and when it is given hemicube rows above it are "
           "cast again by rays; rows that do not meet it are counted and named (default 1e-3; a .vs3's eps sets it)")
        ->default_str("1e-3");
    if (tolerance == RowTolerance::expert) expert(target);
    app.add_option_function<std::string>(
           "--method", [&o](const std::string& word) { set_row_method(word, o); },
           "auto (rays on a mesh of 1000 pieces or more, or of 100 or more with at most 4 patches a piece, without "
           "obstruction-only surfaces; else hemicubes), "
           "hemicube (OpenGL) or raycast (Monte Carlo through Embree, no GL)")
        ->check(CLI::IsMember({"auto", "hemicube", "raycast"}))
        ->default_str("auto");
    expert(app.add_option_function<std::uint64_t>(
           "--rays", [&o](std::uint64_t r) { o.rays = r, o.rays_given = true; },
           "raycast: rays per patch (standard error of F about sqrt(F(1-F)/rays); default 4096 with --method raycast, "
           "max(N^2/2, min(2 N^2, 32768)) where --method auto casts rays)")
        ->default_str("4096"));
    expert(app.add_option("--resolution", o.resolution, "hemicube top-face resolution in pixels (even, 8..8192)")
        ->default_val(256));
    expert(add_word_option(app, "--backend", o.backend, parse_backend, {"auto", "egl", "osmesa"},
                    "OpenGL context: auto (EGL, then OSMesa), egl or osmesa", "auto"));
    app.add_option("--threads", o.threads, "worker threads, one GL context each (default: every core)");
    expert(app.add_flag_function(
        "--no-rotate", [&o](std::int64_t) { o.rotate = false; },
        "do not rotate hemicubes about the normal by a seeded random angle"));
    expert(app.add_option("--seed", o.seed, "seed of the hemicube rotation angles")->default_val(0x5eed));
    expert(add_word_option(app, "--correct", o.correct, parse_correction, {"none", "near"},
                    "near (default): exact form factors for near unoccluded pairs, sender quadrature (hemicube) for "
                    "entries within 64 patch sizes, closed rows kept closed; switched on per row where a row needs "
                    "it. none: the plain rows",
                    "near"));
    expert(app.add_option("--near-k", o.near_k, "--correct near: pairs closer than K x patch size are near")
        ->check(CLI::PositiveNumber)
        ->default_val(3.0));
    expert(app.add_option("--near-min-ff", o.near_min_ff,
                   "--correct near, raycast: a near pair whose form factor is provably below F (A_j / (pi gap^2)) "
                   "keeps its ray estimate, without a shaft test or an exact value (docs/accuracy.md); 0: every near pair")
        ->check(CLI::Range(0.0, 1.0))
        ->default_val(0.03));
    expert(app.add_option("--sub-hemicube-k", o.sub_hemicube_k,
                   "--correct near: a possibly occluded near pair makes its row use sub-hemicubes when it lies within "
                   "K x the sender's size (docs/accuracy.md); 0: every such pair")
        ->check(CLI::NonNegativeNumber)
        ->default_val(10.0));
    expert(app.add_option_function<std::string>(
           "--exact-visibility",
           [&o](const std::string& word) {
               try {
                   parse_exact_visibility(word, o);
               } catch (const InputError& e) {  // a parse error, as CLI11 reports them (exit 2)
                   throw CLI::ValidationError(e.what());
               }
           },
           "--correct near: a possibly occluded near pair with at most K possible occluders in its shaft gets "
           "the exact factor past them instead of sub-hemicubes (docs/accuracy.md). auto (default, hemicube): K = 8 "
           "where it spares a row its sub-hemicubes, within a per-row cost bound; K (at most 64): every such pair, "
           "no bound; 0 or off: never")
        ->default_str("auto"));
    expert(add_word_option(app, "--fine-rows", o.fine_rows, parse_fine_rows, {"auto", "hemicubes", "rays"},
                    "--correct near, hemicube: how rows planned at 4 x 4 sub-hemicubes (an occluder touches the "
                    "sender) are measured. auto (default): ray-cast on scenes of 1000 pieces or more (no "
                    "obstruction-only surfaces), where 16 sub-hemicubes cost more than the rays on llvmpipe; "
                    "hemicubes; rays (docs/accuracy.md, \"Rows an occluder touches, by rays\")",
                    "auto"));
    expert(app.add_option("--fine-row-rays", o.fine_row_rays,
                   "--fine-rows: rays per ray-cast row (default 0: max(N^2/2, min(2 N^2, 32768)): 32768 at N = 128 and 256)")
        ->check(CLI::NonNegativeNumber));
    expert(add_word_option(app, "--far-field", o.far_field, parse_far_field, {"auto", "on", "off"},
                    "--correct near: analytic values for every pair beyond the near range that a plane test proves "
                    "unoccluded. auto (default): where its estimated cost per row is at most 30% of a hemicube "
                    "row's; on: wherever the scene has at most 256 planes; off",
                    "auto"));
    expert(app.add_option_function<std::string>(
           "--cost-model",
           [&o](const std::string& path) {
               try {
                   o.cost_model = read_cost_model(path);
               } catch (const InputError& e) {  // reported as CLI11 reports a bad option (exit 2)
                   throw CLI::ValidationError(e.what());
               }
           },
           "--correct near, hemicube: the costs --far-field auto and --exact-visibility auto weigh, from a file "
           "`ffcube calibrate` wrote on this machine (docs/accuracy.md, \"Cost model\"); default: llvmpipe's, measured "
           "on the development machines")
        ->type_name("FILE"));
}

void add_far_field_emitters_option(CLI::App& app, RowOptions& o) {
    o.far_field_emitters = true;
    expert(app.add_option_function<std::string>(
           "--far-field-emitters", [&o](const std::string& w) { o.far_field_emitters = w == "on"; },
           "--correct near, --far-field auto: where the far field is over budget for every row, keep it for the "
           "emitting patches' rows (they carry the direct term; docs/adaptive.md). on (default) or off")
        ->check(CLI::IsMember({"on", "off"}))
        ->default_str("on"));
}

void add_enforce_option(CLI::App& app, RowOptions& o) {
    add_word_option(app, "--enforce", o.enforce, parse_enforce_request, {"reciprocity", "closure", "both"},
                    "reciprocity, closure or both (closed scenes only) on the finished matrix", "");
}

void add_checkpoint_options(CLI::App& app, CheckpointOptions& o) {
    auto* dir = app.add_option("--checkpoint", o.dir,
                               "stream finished rows to directory DIR (created if missing) so that a killed run can "
                               "be resumed");
    app.add_flag("--resume", o.resume,
                 "continue the checkpoint in --checkpoint DIR: reuse its rows (it must have been made by the same "
                 "scene and settings), compute the rest")
        ->needs(dir);
}

void check_output_path(const std::string& option, const std::string& path) {
    if (path.empty()) return;
    const std::filesystem::path p(path);
    const std::filesystem::path dir = p.has_parent_path() ? p.parent_path() : std::filesystem::path(".");
    std::error_code ec;
    if (!std::filesystem::is_directory(dir, ec))
        throw InputError(fmt::format("{} {}: the directory {} does not exist", option, path, dir.string()));
    if (std::filesystem::is_directory(p, ec))
        throw InputError(fmt::format("{} {}: is a directory, not a file name", option, path));
}

void write_objects_csv(const std::string& path, const Scene& scene, std::span<const Vec3> radiosity) {
    std::vector<std::string> names;
    std::vector<double> areas;
    std::vector<Vec3> b;
    for (const ObjectRadiosity& o : object_radiosity(scene, radiosity)) {
        names.push_back(o.name);
        areas.push_back(o.area);
        b.push_back(o.radiosity);
    }
    write_object_radiosity_csv(path, names, areas, b);
}

}  // namespace ffcube::cli
