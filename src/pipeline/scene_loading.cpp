#include "ffcube/pipeline/scene_loading.hpp"

#include <fmt/format.h>

#include <optional>

#include "ffcube/core/log.hpp"
#include "ffcube/core/timer.hpp"
#include "ffcube/scene/builtin.hpp"
#include "ffcube/scene/contact.hpp"
#include "ffcube/scene/defects.hpp"
#include "ffcube/scene/load_model.hpp"
#include "ffcube/scene/material_map.hpp"
#include "ffcube/scene/mesher.hpp"
#include "ffcube/scene/obj_loader.hpp"

namespace ffcube {

Scene load_and_mesh(const SceneOptions& o, Report& report) {
    validate(o);
    Stopwatch watch;
    ImportedMaterials imported;  // filled by the assimp reader
    ObjLoadOptions load;
    load.objects_by = o.objects_by;
    load.fe = fe_load_options(o);
    ObjModel model = o.path.empty() ? load_cornell_box() : load_model(o.path, o.format, load, &imported);
    const SceneFormat format = o.path.empty() ? SceneFormat::Obj : o.format == SceneFormat::Auto ? format_for_path(o.path) : o.format;
    return mesh_model(std::move(model), o, report, to_string(format), watch.seconds(), imported);
}

FeLoadOptions fe_load_options(const SceneOptions& o) {
    FeLoadOptions fe;
    fe.objects_by = o.fe_objects_by;
    fe.flip = o.flip;
    fe.field = o.fe_field;
    fe.cad_mesh_size = o.max_patch_edge;
    fe.cad_patches = o.patches;
    return fe;
}

Scene mesh_model(ObjModel model, const SceneOptions& o, Report& report, std::string_view format, double read_seconds,
                 const ImportedMaterials& imported) {
    Stopwatch watch;
    if (!o.materials.empty()) apply_material_map_file(model, o.materials);
    for (const auto& w : model.warnings) log_warning(w);
    // Far from its origin the scene is meshed around its own centre (outputs add scene.origin
    // back), then checked for defects before they become rows (docs/robustness.md).
    const Vec3 origin = recentre(model);
    if (origin != Vec3(0.0))
        info("{}: the scene lies far from its origin; meshed around ({:.17g}, {:.17g}, {:.17g}), which outputs add back",
             model.source, origin.x, origin.y, origin.z);
    const DefectStats defects = check_defects(model);
    for (const auto& w : defects.warnings) log_warning(w);
    std::optional<ContactCutStats> cuts;
    if (cuts_contacts(o)) {
        cuts = cut_contacts(model);
        for (const auto& note : cuts->notes) info("{}", note);
        if (cuts->contacts > 0)
            info("contact cuts ({}; off: --contact-cuts off): {} contact polygons cut {} faces into {} (covered area {:.6g})",
                 to_string(o.contact_cuts), cuts->contacts, cuts->receivers, cuts->faces, cuts->covered_area);
        else
            info("contact cuts ({}): no object stands on another, nothing cut", to_string(o.contact_cuts));
    }
    const double load_s = read_seconds + watch.seconds();
    watch.restart();
    MeshOptions mo;
    mo.max_patch_edge = o.max_patch_edge;
    mo.target_patches = o.patches;
    mo.max_patches = patch_limit_for_physical_memory(mo.max_patches);
    mo.subdivide = o.subdivide;
    Scene scene = build_scene(model, mo);
    if (origin != Vec3(0.0)) {
        scene.origin = origin;
        if (scene.drawn) {
            auto drawn = std::make_shared<Scene>(*scene.drawn);
            drawn->origin = origin;
            scene.drawn = std::move(drawn);
        }
    }
    const double mesh_s = watch.seconds();
    for (const auto& w : scene.stats.warnings) log_warning(w);
    info("scene {}: {} faces, {} objects -> {} patches ({})", scene.source, scene.stats.input_faces, scene.objects.size(),
         scene.size(), scene.stats.how);
    if (scene.stats.dropped_degenerate) info("dropped {} degenerate (zero-area) faces", scene.stats.dropped_degenerate);
    if (model.dropped_degenerate) info("the loader dropped {} degenerate facets", model.dropped_degenerate);
    if (model.merged_vertices) info("the loader merged {} coinciding vertex references", model.merged_vertices);
    report.set("scene", scene.source);
    report.set("patches", scene.size());
    report.set("objects", scene.objects.size());
    report.set("meshing.max_patch_edge", scene.stats.max_patch_edge);
    report.set("meshing.how", scene.stats.how);
    report.set("meshing.input_faces", scene.stats.input_faces);
    report.set("meshing.dropped_degenerate", scene.stats.dropped_degenerate);
    report.set("meshing.non_planar", scene.stats.non_planar);
    report.set("meshing.triangulated_ngons", scene.stats.triangulated_ngons);
    report.set("meshing.contact_cuts.mode", to_string(o.contact_cuts));
    report.set("meshing.contact_cuts.enabled", cuts.has_value());
    report.set("meshing.contact_cuts.fired", cuts.has_value() && cuts->contacts > 0);
    if (cuts) {
        report.set("meshing.contact_cuts.contacts", cuts->contacts);
        report.set("meshing.contact_cuts.receivers", cuts->receivers);
        report.set("meshing.contact_cuts.faces", cuts->faces);
        report.set("meshing.contact_cuts.covered_area", cuts->covered_area);
        report.set("meshing.contact_cuts.skipped", cuts->skipped);
    }
    report.set("loading.format", std::string(format));
    report.set("loading.dropped_degenerate", model.dropped_degenerate);
    report.set("loading.merged_vertices", model.merged_vertices);
    report.set("loading.duplicates_removed", defects.duplicates_removed);
    report.set("loading.two_sided_pairs", defects.two_sided_pairs);
    report.set("loading.recentred", origin != Vec3(0.0));
    if (const ImportedMaterials& m = imported; m.present) {
        // The assimp reader's material mapping (docs/scene-format.md, "Materials through assimp").
        info("materials: {} in the file; faces: {} from a material, {} from vertex colours, {} default (Kd 0.5, Ke 0); {} "
             "textured material{} (textures ignored){}",
             m.from_file, m.faces_material, m.faces_vertex_colour, m.faces_default, m.textured, m.textured == 1 ? "" : "s",
             o.materials.empty() ? "" : "; --materials overrides the objects it names");
        report.set("loading.materials.from_file", m.from_file);
        report.set("loading.materials.faces_material", m.faces_material);
        report.set("loading.materials.faces_vertex_colour", m.faces_vertex_colour);
        report.set("loading.materials.faces_default", m.faces_default);
        report.set("loading.materials.textured_ignored", m.textured);
    }
    if (scene.drawn) {
        // View3D's O surfaces: drawn (they block), no row, no column (docs/scene-format.md).
        const std::size_t o_patches = scene.drawn->size() - scene.size();
        info("{} obstruction-only surfaces ({} patches, drawn from both sides): no rows, no columns", model.obstruction_objects,
             o_patches);
        report.set("obstruction.surfaces", model.obstruction_objects);
        report.set("obstruction.patches", o_patches);
        report.set("obstruction.rows_not_computed", o_patches);
    }
    report.set("fingerprint", fmt::format("{:016x}", scene.fingerprint));
    report.set("time.loading", load_s);
    report.set("time.meshing", mesh_s);
    return scene;
}

}  // namespace ffcube
