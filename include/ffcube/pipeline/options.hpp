// The options that say how a scene is loaded and how its rows are made, parsed once into enums
// and numbers. Every front end fills one of these (the command line from its flags, the bench
// from its settings, the Python module from keyword arguments) and hands it to the one factory in
// pipeline/row_source.hpp, so the same options give the same rows everywhere.
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <string_view>

#include "ffcube/accuracy/enforce.hpp"
#include "ffcube/accuracy/near_field.hpp"
#include "ffcube/gl/context.hpp"
#include "ffcube/gl/hemicube_provider.hpp"
#include "ffcube/pipeline/cost_model.hpp"
#include "ffcube/pipeline/row_engine.hpp"
#include "ffcube/raycast/raycast_provider.hpp"
#include "ffcube/scene/obj_loader.hpp"
#include "ffcube/scene/load_model.hpp"

namespace ffcube {

// Where the scene comes from and how it is meshed.

// --contact-cuts (scene/contact.hpp, docs/adaptive.md): cut receiver faces along the polygons where
// other objects stand on them before meshing. Auto (the default): on for every command that meshes
// (it cuts only where the scene has contacts, and says so), off with --no-subdivide.
enum class ContactCuts { Auto, On, Off };
struct SceneOptions {
    std::string path;            // empty: the built-in Cornell box
    double max_patch_edge = 0;   // > 0: split faces so that no patch edge exceeds it
    std::size_t patches = 0;     // > 0: mesh to about this many patches (default of the mesher otherwise)
    ObjObjectsBy objects_by = ObjObjectsBy::automatic;  // OBJ: what names objects (--objects-by)
    FeObjectsBy fe_objects_by = FeObjectsBy::group;     // meshes read through Gmsh: the same (--objects-by)
    std::vector<std::string> flip;                      // --flip GROUP: reversed objects of a mesh file
    std::string fe_field;  // --objects-by field:NAME: a legacy .vtk's integer cell array NAME names objects
    SceneFormat format = SceneFormat::Auto;  // --format: Auto = by the file's extension
    std::string materials;       // --materials: CSV of Kd and Ke per object (scene/material_map.hpp)
    bool subdivide = true;       // false (--no-subdivide): one patch per input face
    ContactCuts contact_cuts = ContactCuts::Auto;  // load_and_mesh: cuts_contacts(o)
};

enum class RowMethod { Hemicube, Raycast };
enum class Correction { None, Near };
using FarFieldMode = NearFieldOptions::FarField;
// --enforce: both = closure (which implies reciprocity); kept apart for the record.
enum class EnforceRequest { None, Reciprocity, Closure, Both };

// --exact-visibility K: at most this many possible occluders (validate(RowOptions) refuses more).
constexpr std::size_t kMaxExactVisibilityOccluders = 64;

// --tolerance's default. Issue 40 asks for View3D's default eps, 1e-4; ray-cast rows refined to
// 1e-4 cost about 18 times the old fixed count on a city (docs/accuracy.md, "Accuracy by target":
// measured), so the default is 1e-3 until a cheaper estimate and hemicube refinement exist.
constexpr double kDefaultTolerance = 1e-3;

struct RowOptions {
    RowMethod method = RowMethod::Hemicube;
    // --method auto: resolve_row_method picks the method from the scene; a named method
    // (set_row_method) clears it. The command line and Python start with it on (their default
    // is auto); a RowOptions made in code keeps `method` as set. auto_raycast: resolve_row_method
    // chose the ray caster.
    bool method_auto = false;
    bool auto_raycast = false;
    std::string method_choice;  // resolve_row_method's reason, for the report ("" when named)
    // With a --cost-model file, the costs resolve_row_method weighed (pipeline/row_engine.hpp).
    MethodCosts method_costs;
    // Hemicube (gl/hemicube_provider.hpp): top-face pixels (hemicube/layout.hpp's rule), context.
    int resolution = 256;
    Backend backend = Backend::Auto;
    bool rotate = true;
    // Both methods: worker threads (0: every core) and the seed of angles or rays.
    unsigned threads = 0;
    std::uint64_t seed = 0x5eed;
    // Hemicube workers may be forked processes (HemicubeOptions::worker_processes); the MPI
    // commands set false. Rows do not depend on it.
    bool worker_processes = true;
    // Ray caster: rays per patch (≥ 1). rays_given: set by --rays (else --method auto's ray caster
    // casts the fine-row count, default_fine_row_rays in pipeline/row_engine.hpp).
    std::uint64_t rays = 4096;
    bool rays_given = false;
    // Accuracy by target (--tolerance E, docs/accuracy.md): the largest error a row may keep in
    // any entry and in its sum. 0 (a RowOptions made in code): off, rows at fixed counts. The
    // command line and Python start at kDefaultTolerance; a .vs3's eps sets it when they give
    // none (tolerance_given false), and then counts as given. Ray-cast rows are refined to it
    // unless --rays fixes their count; hemicube rows above it are measured again by rays refined
    // to it when it was given (refine_hemicube_rows, pipeline/row_source.hpp).
    double tolerance = 0;
    bool tolerance_given = false;
    // The near-field correction (accuracy/near_field.hpp) and its far field.
    Correction correct = Correction::Near;
    double near_k = 3.0;
    // NearFieldOptions::min_near_value for the ray caster's rows (--near-min-ff; 0: every near
    // pair): 0.03 keeps a city's rows within 1% of every pair's (docs/accuracy.md). The hemicube
    // ignores it.
    double near_min_ff = 0.03;
    double sub_hemicube_k = 10.0;  // NearFieldOptions::sub_hemicube_k (0: every refused near pair)
    // NearFieldOptions::exact_visibility_occluders (0: off). With exact_visibility_auto (the
    // default, `--exact-visibility auto`) the hemicube uses kAutoExactVisibilityOccluders within
    // the per-row budget exact_visibility_budget_for_hemicube; the ray caster none (its rows are
    // not sampled by sub-hemicubes, so there is no cost to spare). An explicit K: no budget.
    std::size_t exact_visibility_occluders = 0;
    FarFieldMode far_field = FarFieldMode::automatic;
    bool exact_visibility_auto = true;  // `--exact-visibility auto` (above); a number or `off` clears it
    // --fine-rows auto|hemicubes|rays, --fine-row-rays R (0: max(N²/2, min(2 N², 32,768))): rows
    // planned at 4 × 4 ray-cast instead, automatically on scenes of many pieces (the driver's
    // engine_for_row, pipeline/row_engine.hpp).
    FineRows fine_rows = FineRows::automatic;
    std::uint64_t fine_row_rays = 0;
    // HemicubeOptions::occlusion_culling (--occlusion-culling on|off): the same rows either way;
    // off leaves out the occluders' depth pass and the tests (docs/architecture.md, "Culling").
    bool occlusion_culling = true;
    // HemicubeOptions::enclosure_without_depth (--enclosure on|off): a convex room's walls or a
    // flat ground drawn without the depth test from eyes inside; the same rows but for ties on
    // contact lines, which the piece standing in front now wins.
    bool enclosure_without_depth = true;
    // On the finished matrix (formfactors only).
    EnforceRequest enforce = EnforceRequest::None;
    // Who asked for it when the command line did not: "room.vs3:3: encl=1" (apply_view3d_controls);
    // enforcement's refusals then name it (pipeline/enforcement.cpp).
    std::string enforce_origin;
    // What `--far-field auto` and `--exact-visibility auto` weigh (--cost-model FILE; built-in:
    // llvmpipe on the development machines).
    CostModel cost_model;
    // NearFieldOptions::far_field_emitters (hemicube, --correct near): the far field on the
    // emitting rows only where automatic mode finds it over budget for every row. `ffcube solve`
    // (--far-field-emitters on|off) and Python's solve() turn it on by default; formfactors keeps
    // its rows as before (off).
    bool far_field_emitters = false;
};

// Parsers of the command line's words; each throws InputError naming the option and the words
// it accepts.
RowMethod parse_row_method(std::string_view text);        // hemicube | raycast
// --method: auto | hemicube | raycast, into method and method_auto.
void set_row_method(std::string_view text, RowOptions& o);
Correction parse_correction(std::string_view text);       // none | near
FarFieldMode parse_far_field(std::string_view text);      // auto | on | off
FineRows parse_fine_rows(std::string_view text);                    // auto | hemicubes | rays
EnforceRequest parse_enforce_request(std::string_view text);  // "" | reciprocity | closure | both
// --exact-visibility: auto | off | K (a number; its range is checked by validate(RowOptions)).
void parse_exact_visibility(std::string_view text, RowOptions& o);
ContactCuts parse_contact_cuts(std::string_view text);    // auto | on | off
// Whether load_and_mesh cuts contacts: On, or Auto with subdivision (a cut face is not one patch).
bool cuts_contacts(const SceneOptions& o);
const char* to_string(ContactCuts c);
std::string_view to_string(RowMethod m);

// --method auto, resolved for the scene whose rows are made (its drawn scene): the ray caster
// where rays_preferred (pipeline/row_engine.hpp: a mesh of 1,000 facets or more, or of 100 or more with
// one patch a facet or nearly), no obstruction-only surfaces (the ray caster credits either side of them) and
// --fine-rows is not hemicubes; there, on llvmpipe, a row of 65,536 rays cost a third of one
// hemicube that draws the whole city and is more accurate (docs/accuracy.md, "Rows by rays on a
// mesh of many pieces"; docs/benchmarks.md, "Rays in coherent packets"). Its rays: --rays if given, else --fine-row-rays, else
// default_fine_row_rays(--resolution). Everywhere else the hemicube. That is the built-in cost
// model's rule; with a --cost-model file the costs decide instead (scene_method_costs: rays where
// a ray-cast row, at expected_row_rays, costs less than the mesh's typical hemicube row), still
// never with obstruction-only surfaces or --fine-rows hemicubes. Options without method_auto come
// back as they are.
RowOptions resolve_row_method(const RowOptions& o, const Scene& drawn);
std::string_view to_string(Correction c);
std::string_view to_string(FarFieldMode f);
std::string_view to_string(EnforceRequest e);

// Refuses inconsistent or out-of-range options (InputError naming the option) before any work.
void validate(const SceneOptions& o);
void validate(const RowOptions& o);

// The options of each layer, as these RowOptions give them.
HemicubeOptions hemicube_options(const RowOptions& o);
// Whether the ray caster's rows are refined to o.tolerance (a tolerance, and no --rays).
bool rays_refined(const RowOptions& o);
RaycastOptions raycast_options(const RowOptions& o);
// Only meaningful with correct == Near.
NearFieldOptions near_field_options(const RowOptions& o);
// Only meaningful with enforce != None.
EnforceMode enforce_mode(EnforceRequest e);

}  // namespace ffcube
