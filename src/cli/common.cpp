#include "cli/common.hpp"

#include <fmt/format.h>
#include <unistd.h>

#include <algorithm>
#include <numbers>

#include "ffcube/accuracy/enforce.hpp"
#include "ffcube/core/error.hpp"
#include "ffcube/core/log.hpp"
#include "ffcube/core/timer.hpp"
#include "ffcube/scene/builtin.hpp"
#include "ffcube/scene/obj_loader.hpp"

namespace ffcube::cli {

void add_scene_options(CLI::App& app, SceneOptions& o) {
    app.add_option("scene", o.scene, "Wavefront OBJ scene (default: the built-in Cornell box)");
    auto* edge = app.add_option("--max-patch-edge", o.max_patch_edge, "split faces so that no patch edge exceeds L (scene units)")
                     ->check(CLI::PositiveNumber);
    app.add_option("--patches", o.patches, "mesh to about N patches (default: 2000)")->check(CLI::PositiveNumber)->excludes(edge);
    app.add_option("--objects-by", o.objects_by,
                   "what names objects in an OBJ: auto (default: o, else g, else the material), o, g or material")
        ->check(CLI::IsMember({"auto", "o", "g", "material"}))
        ->default_val("auto");
    app.add_flag("-q,--quiet", o.quiet, "no progress or summary on stderr (warnings and errors still)");
}

void add_formfactor_options(CLI::App& app, FormFactorOptions& o) {
    app.add_option("--method", o.method, "hemicube (OpenGL) or raycast (Monte Carlo through Embree, no GL)")
        ->check(CLI::IsMember({"hemicube", "raycast"}))
        ->default_val("hemicube");
    app.add_option("--rays", o.rays, "raycast: rays per patch (standard error of F about sqrt(F(1-F)/rays))")
        ->default_val(4096);
    app.add_option("--resolution", o.resolution, "hemicube top-face resolution in pixels (even, 8..8192)")
        ->default_val(256);
    app.add_option("--backend", o.backend, "OpenGL context: auto (EGL, then OSMesa), egl or osmesa")
        ->check(CLI::IsMember({"auto", "egl", "osmesa"}))
        ->default_val("auto");
    app.add_option("--threads", o.threads, "worker threads, one GL context each (default: every core)");
    app.add_flag("--no-rotate", o.no_rotate, "do not rotate hemicubes about the normal by a seeded random angle");
    app.add_option("--seed", o.seed, "seed of the hemicube rotation angles")->default_val(0x5eed);
    app.add_option("--correct", o.correct,
                   "near (default): exact form factors for near unoccluded pairs, sender quadrature (hemicube) for "
                   "entries within 64 patch sizes, closed rows kept closed; switched on per row where a row needs it. "
                   "none: the plain rows")
        ->check(CLI::IsMember({"none", "near"}))
        ->default_val("near");
    app.add_option("--near-k", o.near_k, "--correct near: pairs closer than K x patch size are near")
        ->check(CLI::PositiveNumber)
        ->default_val(3.0);
    app.add_option("--far-field", o.far_field,
                   "--correct near: analytic values for every pair beyond the near range that a plane test proves "
                   "unoccluded. auto (default): where its estimated cost per row is at most 30% of a hemicube "
                   "row's; on: wherever the scene has at most 256 planes; off")
        ->check(CLI::IsMember({"auto", "on", "off"}))
        ->default_val("auto");
}

void add_enforce_option(CLI::App& app, FormFactorOptions& o) {
    app.add_option("--enforce", o.enforce, "reciprocity, closure or both (closed scenes only) on the finished matrix")
        ->check(CLI::IsMember({"reciprocity", "closure", "both"}));
}

namespace {

// The mesher refuses a mesh above MeshOptions::max_patches before allocating it. Lower that
// limit to what this machine's physical memory can hold at the mesher's own estimate of bytes per
// patch (a Patch and about one vertex), so that a too-small --max-patch-edge is refused with the
// estimate instead of ending in the out-of-memory killer. The form-factor rows need more (see
// docs/robustness.md), but that depends on the resolution and is not known before meshing.
std::size_t patch_limit_for_this_machine(std::size_t limit) {
    const long pages = sysconf(_SC_PHYS_PAGES), page = sysconf(_SC_PAGE_SIZE);
    if (pages <= 0 || page <= 0) return limit;
    const double bytes = static_cast<double>(pages) * static_cast<double>(page);
    return std::min(limit, static_cast<std::size_t>(bytes / static_cast<double>(sizeof(Patch) + sizeof(Vec3))));
}

}  // namespace

Scene load_and_mesh(const SceneOptions& o, Report& report) {
    Stopwatch watch;
    ObjModel model = o.scene.empty() ? load_cornell_box() : load_obj(o.scene, {parse_objects_by(o.objects_by)});
    for (const auto& w : model.warnings) log_warning(w);
    const double load_s = watch.seconds();
    watch.restart();
    MeshOptions mo;
    mo.max_patch_edge = o.max_patch_edge;
    mo.target_patches = o.patches;
    mo.max_patches = patch_limit_for_this_machine(mo.max_patches);
    Scene scene = build_scene(model, mo);
    const double mesh_s = watch.seconds();
    for (const auto& w : scene.stats.warnings) log_warning(w);
    info("scene {}: {} faces, {} objects -> {} patches ({})", scene.source, scene.stats.input_faces, scene.objects.size(),
         scene.size(), scene.stats.how);
    if (scene.stats.dropped_degenerate) info("dropped {} degenerate (zero-area) faces", scene.stats.dropped_degenerate);
    report.set("scene", scene.source);
    report.set("patches", scene.size());
    report.set("objects", scene.objects.size());
    report.set("meshing.max_patch_edge", scene.stats.max_patch_edge);
    report.set("meshing.how", scene.stats.how);
    report.set("meshing.input_faces", scene.stats.input_faces);
    report.set("meshing.dropped_degenerate", scene.stats.dropped_degenerate);
    report.set("meshing.non_planar", scene.stats.non_planar);
    report.set("meshing.triangulated_ngons", scene.stats.triangulated_ngons);
    report.set("fingerprint", fmt::format("{:016x}", scene.fingerprint));
    report.set("time.loading", load_s);
    report.set("time.meshing", mesh_s);
    return scene;
}

HemicubeOptions hemicube_options(const FormFactorOptions& o) {
    HemicubeOptions h;
    h.resolution = o.resolution;
    h.backend = parse_backend(o.backend);
    h.threads = o.threads;
    h.rotate = !o.no_rotate;
    h.seed = o.seed;
    if (h.resolution < 8 || h.resolution > 8192 || h.resolution % 2 != 0)
        throw InputError(fmt::format("--resolution {}: must be an even number of pixels from 8 to 8192", h.resolution));
    return h;
}

FfmMetadata row_metadata(const FormFactorOptions& o) {
    FfmMetadata meta;
    meta.method = o.method;
    if (o.method == "raycast") {
        meta.settings = fmt::format("rays={} seed={}", o.rays, o.seed);
    } else {
        meta.resolution = static_cast<std::uint32_t>(o.resolution);
        meta.settings = fmt::format("rotate={} seed={}", o.no_rotate ? 0 : 1, o.seed);
    }
    // Corrected rows differ from plain ones: checkpoints and matrices must not mix them.
    if (o.correct == "near") meta.settings += fmt::format(" correct=near k={}", o.near_k);
    if (o.correct == "near" && o.far_field != "auto") meta.settings += fmt::format(" far_field={}", o.far_field);
    return meta;
}

RowSource make_row_source(const Scene& scene, const FormFactorOptions& o, Report& report) {
    RowSource rows;
    Stopwatch watch;
    if (o.method == "raycast") {
        if (o.rays == 0) throw InputError("--rays 0: at least 1 ray per patch");
        RaycastOptions ropt;
        ropt.rays = o.rays;
        ropt.threads = o.threads;
        ropt.seed = o.seed;
        rows.raycast = std::make_unique<RaycastRowProvider>(scene, ropt);
        info("raycast (Embree), {} thread(s), {} rays per patch", rows.raycast->threads(), rows.raycast->rays());
    } else {
        rows.hemicube = std::make_unique<HemicubeRowProvider>(scene, hemicube_options(o));
        const HemicubeRowProvider& h = *rows.hemicube;
        info("hemicube on {} ({}), {} {}, resolution {}", h.backend(), h.renderer(), h.threads(), h.workers(), h.resolution());
    }
    if (o.correct == "near") {
        NearFieldOptions nf;
        nf.k = o.near_k;
        if (rows.hemicube) {
            nf = near_field_options_for_hemicube(o.resolution, o.near_k);
            if (o.far_field == "on") nf.far_field = NearFieldOptions::FarField::on;
            if (o.far_field == "off") nf.far_field = NearFieldOptions::FarField::off;
        } else {
            // The ray caster samples the whole sender (no sender quadrature); its noise, for the
            // per-row error estimate.
            nf.rays = static_cast<double>(o.rays);
        }
        RowProvider& inner = rows.hemicube ? static_cast<RowProvider&>(*rows.hemicube) : *rows.raycast;
        rows.corrected = std::make_unique<CorrectedRowProvider>(scene, inner, nf);
        info("near-field correction: k = {}{}, far field {}", nf.k, nf.sender_quadrature ? ", sender quadrature" : "",
             rows.corrected->corrector().far_field_status());
    }
    report.set("method", rows.provider().name());
    report.set("time.setup", watch.seconds());
    return rows;
}

void report_row_source(Report& r, const RowSource& rows) {
    if (rows.corrected) {
        const NearFieldStats& c = rows.corrected->stats();
        r.set("corrections.kind", "near");
        r.set("corrections.rows", c.rows);
        r.set("corrections.rows_touched", c.rows_touched);
        r.set("corrections.near_pairs", c.near_pairs);
        r.set("corrections.entries_replaced", c.replaced);
        r.set("corrections.pairs_refused_possibly_occluded", c.refused);
        r.set("corrections.entries_quadrature", c.quadrature);
        r.set("corrections.rows_quadrature", c.rows_quadrature);
        r.set("corrections.rows_untouched", c.rows_untouched);
        r.set("corrections.rows_closed_rebalanced", c.rows_closed);
        r.set("corrections.rows_capped_at_one", c.rows_capped);
        r.set("corrections.rows_sub_hemicubes", c.rows_sampled);
        r.set("corrections.small_receiver_entries", c.small_receiver_entries);
        r.set("corrections.far_field", rows.corrected->corrector().far_field_status());
        r.set("corrections.far_field_planes", rows.corrected->corrector().far_field_planes());
        if (const double ns = rows.corrected->corrector().far_field_cost_ns(); std::isfinite(ns))
            r.set("corrections.far_field_estimated_ms_per_row", ns * 1e-6);
        r.set("corrections.far_field_rows", c.far_rows);
        r.set("corrections.far_field_entries", c.far_entries);
        r.set("corrections.far_field_pairs_unproven", c.far_unproven);
        r.set("corrections.rows_analytic", c.rows_analytic);
        r.set("corrections.rows_with_small_receivers", c.rows_with_small_receivers);
        r.set("corrections.rebalance_max_change", c.closed_scale_max_change);
        // Per-row error estimate (Σ_j |F_ij − exact_ij|, docs/accuracy.md): every computed row,
        // then the largest, the mean and the row that has the largest.
        const std::vector<float>& est = rows.corrected->row_error_estimates();
        std::vector<double> values;
        double mx = 0, sum = 0;
        std::int64_t worst = -1;
        std::uint64_t counted = 0;
        for (std::size_t i = 0; i < est.size(); ++i) {
            values.push_back(std::isnan(est[i]) ? -1.0 : static_cast<double>(est[i]));
            if (std::isnan(est[i])) continue;
            ++counted;
            sum += est[i];
            if (est[i] > mx || worst < 0) {
                mx = est[i];
                worst = static_cast<std::int64_t>(i);
            }
        }
        r.set("row_error_estimate.max", mx);
        r.set("row_error_estimate.mean", counted ? sum / static_cast<double>(counted) : 0.0);
        r.set("row_error_estimate.worst_row", worst);
        r.set_array("row_error_estimate.rows", values);
        r.set("corrections.seconds", c.seconds);
        r.set("corrections.near_seconds", c.near_seconds);
        r.set("corrections.quadrature_seconds", c.quadrature_seconds);
    }
    if (rows.raycast) {
        r.set("rays_per_patch", rows.raycast->rays());
        r.set("rays_traced", rows.raycast->rays_traced());
        r.set("threads", rows.raycast->threads());
        return;
    }
    const HemicubeRowProvider& provider = *rows.hemicube;
    const HemicubeStats st = provider.stats();
    r.set("backend", provider.backend());
    r.set("renderer", provider.renderer());
    r.set("resolution", provider.resolution());
    r.set("threads", provider.threads());
    r.set("workers", provider.workers());
    r.set("hemicubes", st.hemicubes);
    // CPU-seconds summed over workers.
    r.set("time.prepare", st.prepare_seconds);
    r.set("time.drawing", st.draw_seconds);
    r.set("time.readback", st.readback_seconds);
    r.set("time.accumulation", st.accumulate_seconds);
    // Culling is per mesher piece (a face's quad or triangle, drawn whole), summed over hemicubes.
    r.set("left_out.pieces_considered", st.pieces_considered);
    r.set("left_out.pieces_behind_plane", st.pieces_behind);
    const char* names[5] = {"top", "pos_x", "neg_x", "pos_y", "neg_y"};
    for (std::size_t f = 0; f < 5; ++f) {
        r.set(fmt::format("left_out.pieces_culled_per_face.{}", names[f]), st.pieces_culled[f]);
        r.set(fmt::format("drawn.pieces_per_face.{}", names[f]), st.pieces_drawn[f]);
    }
    const double h = st.hemicubes ? static_cast<double>(st.hemicubes) : 1.0;
    r.set("coverage.mean_miss_fraction", st.miss_weight / h);
    r.set("coverage.mean_back_face_fraction", st.back_face_weight / h);
    r.set("self_hits", st.self_hits);
    r.set("sub_hemicube_rows", st.sampled_rows);
    r.set("rows_not_rendered", st.skipped_rows);
}

CsrMatrix apply_enforcement(const FormFactorOptions& o, CsrMatrix F, const Scene& scene, const RowSource& rows,
                            Report& report) {
    if (o.enforce.empty()) return F;
    const EnforceMode mode = parse_enforce_mode(o.enforce);
    if (mode == EnforceMode::Closure) {
        if (rows.hemicube && rows.hemicube->stats().miss_weight > 0)
            throw InputError(fmt::format(
                "--enforce {}: hemicube pixels saw nothing (ΔF {:.3g} summed over hemicubes): the scene is open (light "
                "escapes), and closure would hide that",
                o.enforce, rows.hemicube->stats().miss_weight));
        // Ray-cast rows of a closed scene sum to 1 up to rays lost at cracks; 1e-3 tolerates few.
        // Corrected rows are judged as the inner provider made them (see NearFieldStats).
        if (rows.corrected) {
            const double s = rows.corrected->stats().inner_row_sum_min;
            if (s < 1.0 - 1e-3)
                throw InputError(fmt::format("--enforce {}: a row sums to {:.6g} < 1 - 0.001 before correction: the scene "
                                             "is open (light escapes), and closure would hide that",
                                             o.enforce, s));
        } else {
            require_closed(F, 1e-3);
        }
    }
    std::vector<double> areas;
    areas.reserve(scene.size());
    for (const Patch& p : scene.patches) areas.push_back(p.area);
    EnforceStats st;
    Stopwatch watch;
    const EnforcedMatrix E = enforce(F, areas, mode, st);
    report.set("enforce.mode", o.enforce);
    for (const auto& [when, f] : {std::pair{"before", st.before}, std::pair{"after", st.after}}) {
        report.set(fmt::format("enforce.{}.row_sum_min", when), f.row_sum_min);
        report.set(fmt::format("enforce.{}.row_sum_max", when), f.row_sum_max);
        report.set(fmt::format("enforce.{}.reciprocity_max", when), f.reciprocity_max);
    }
    report.set("enforce.iterations", st.iterations);
    report.set("enforce.seconds", watch.seconds());
    info("--enforce {}: row sums {:.6f}..{:.6f} -> {:.6f}..{:.6f}, reciprocity {:.2e} -> {:.2e} (in double; stored as float)",
         o.enforce, st.before.row_sum_min, st.before.row_sum_max, st.after.row_sum_min, st.after.row_sum_max,
         st.before.reciprocity_max, st.after.reciprocity_max);
    return E.to_csr();
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

}  // namespace ffcube::cli
