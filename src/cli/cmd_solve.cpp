// ffcube solve: radiosity of a scene (rows from hemicubes or from a .ffm file), with its results
// as CSV, a JSON report, a picture (EXR or PNG) and a coloured mesh (PLY). docs/solve.md.
#include <fmt/format.h>

#include <array>
#include <memory>
#include <cmath>
#include <numbers>
#include <optional>

#include "cli/commands.hpp"
#include "cli/common.hpp"
#include "cli/mpi_glue.hpp"
#include "ffcube/core/error.hpp"
#include "ffcube/core/log.hpp"
#include "ffcube/core/timer.hpp"
#include "ffcube/io/csv.hpp"
#include "ffcube/io/ffm.hpp"
#include "ffcube/io/ply.hpp"
#include "ffcube/pipeline/row_source.hpp"
#include "ffcube/pipeline/scene_loading.hpp"
#include "ffcube/render/renderer.hpp"
#include "ffcube/render/solved_scene.hpp"
#include "ffcube/solver/solver.hpp"

namespace ffcube::cli {
namespace {

// Shooters asked from the row provider per call (SolverOptions::batch): enough to keep 16
// hemicube workers busy. Fixed rather than the thread count, because the shooting order (and so B
// in its last digits) depends on the batch, and results must not depend on the thread count.
constexpr std::uint32_t kShotBatch = 16;

struct Options {
    SceneFlags scene;
    RowOptions rows;
    std::string solver = "shoot";
    double tolerance = 1e-4;
    std::uint64_t max_iterations = 0;
    CLI::Option* overshoot_option = nullptr;  // unbound: 0 or 1 values, parsed in run()
    double row_cache_mb = 512.0;
    std::string matrix, objects, radiosity, report, render, mesh, camera;
    int width = 512, height = 512;
    bool flat = false;
    double exposure = 0.0;  // 0: automatic
    CLI::Option* exposure_option = nullptr;
    bool allow_unconverged = false;
};

void report_vec3(Report& r, std::string_view key, const Vec3& v) {
    const std::array<double, 3> a{v.r, v.g, v.b};
    r.set_array(key, a);
}


void report_result(Report& r, const SolveResult& res, const SolverOptions& so, std::size_t patches) {
    r.set("solver.method", to_string(res.method));
    r.set("solver.tolerance", so.tolerance);
    r.set("solver.max_iterations", effective_max_iterations(so, patches));
    r.set("solver.overshoot", so.overshoot);
    r.set("solver.row_cache_mb", so.row_cache_mb);
    r.set("solver.batch", so.batch);
    r.set("iterations", res.iterations);
    r.set("shots", res.shots);
    r.set("unshot_fraction", res.unshot_fraction);
    r.set("stop_reason", to_string(res.stop));
    r.set("converged", res.converged());
    report_vec3(r, "error_bound.mean_abs", res.error_bound);
    r.set("error_bound.relative", res.error_bound_relative);
    r.set("ambient_included", res.ambient_included);
    const StiffnessReport& st = res.stiffness;
    r.set("stiffness.rho_max", st.rho_max);
    r.set("stiffness.max_row_sum", st.max_row_sum);
    r.set("stiffness.predicted_generations", st.predicted_generations);
    r.set("stiffness.decay_per_window", st.decay_per_window);
    r.set("stiffness.window_shots", st.window_shots);
    r.set("stiffness.predicted_shots", st.predicted_shots);
    r.set("stiffness.stiff", st.stiff);
    r.set("stiffness.action", st.action);
    r.set("stiffness.reason", st.reason);
    r.set("stiffness.switched_at_shot", st.switched_at_shot);
    r.set("stiffness.krylov_products", st.krylov_products);
    r.set("stiffness.finish_rows_computed", st.finish_rows_computed);
    report_vec3(r, "energy.emitted", res.energy.emitted);
    report_vec3(r, "energy.absorbed", res.energy.absorbed);
    report_vec3(r, "energy.escaped", res.energy.escaped);
    report_vec3(r, "energy.unshot", res.energy.unshot);
    r.set("energy.relative_error", res.energy.relative_error);
    report_vec3(r, "ambient", res.ambient);
    r.set("time.solve_total", res.timings.total);
    r.set("time.rows", res.timings.rows);
    r.set("time.solving", res.timings.solve);
    std::vector<double> seconds, fraction;
    for (const ConvergenceSample& s : res.history) {
        seconds.push_back(s.seconds);
        fraction.push_back(s.unshot_fraction);
    }
    r.set_array("history.seconds", seconds);
    r.set_array("history.unshot_fraction", fraction);
    r.set("row_cache.rows_computed", res.cache.rows_computed);
    r.set("row_cache.rows_reused", res.cache.rows_reused);
    r.set("row_cache.rows_evicted", res.cache.rows_evicted);
    r.set("row_cache.rows_recomputed", res.cache.rows_recomputed);
    r.set("row_cache.patches_without_row", res.cache.patches_without_row);
    r.set("row_cache.capacity_bytes", res.cache.capacity_bytes);
    r.set("row_cache.peak_bytes", res.cache.peak_bytes);
    r.set_array("warnings", res.warnings);
}

int run(const Options& o) {
    // Everything that can be refused is refused before any work.
    SolverOptions so;
    so.method = parse_solver_method(o.solver);
    so.tolerance = o.tolerance;
    so.max_iterations = o.max_iterations;
    if (o.overshoot_option && o.overshoot_option->count() > 0) {
        // Given alone, CLI11 records no value (or an empty one): the documented default factor.
        const std::vector<std::string>& given = o.overshoot_option->results();
        const std::string text = given.empty() ? "" : given.back();
        so.overshoot = kDefaultOvershoot;
        if (!text.empty()) {
            std::size_t used = 0;
            try {
                so.overshoot = std::stod(text, &used);
            } catch (const std::exception&) {
                used = 0;
            }
            if (used != text.size()) throw InputError(fmt::format("--overshoot {}: not a number", text));
        }
    }
    so.row_cache_mb = o.row_cache_mb;
    so.batch = kShotBatch;
    validate(so);
    const bool exr = o.render.ends_with(".exr"), png = o.render.ends_with(".png");
    if (!o.render.empty() && !exr && !png)
        throw InputError(fmt::format("--render {}: the name must end in .exr (linear float) or .png (tone-mapped)", o.render));
    if (!o.mesh.ends_with(".ply") && !o.mesh.empty())
        throw InputError(fmt::format("--mesh {}: the name must end in .ply", o.mesh));
    if (o.width < 1 || o.width > 16384 || o.height < 1 || o.height > 16384)
        throw InputError(fmt::format("--width {} --height {}: each must be 1..16384 pixels", o.width, o.height));
    if (o.exposure_option && o.exposure_option->count() > 0 && !(o.exposure > 0.0 && std::isfinite(o.exposure)))
        throw InputError(fmt::format("--exposure {}: must be a finite number > 0", o.exposure));
    for (const auto& [option, path] : {std::pair{"--objects", &o.objects}, {"--radiosity", &o.radiosity},
                                       {"--report", &o.report}, {"--render", &o.render}, {"--mesh", &o.mesh}})
        check_output_path(option, *path);
    validate(o.rows);
    std::optional<Camera> camera;
    if (!o.camera.empty()) camera = parse_camera(o.camera);

    Stopwatch total;
    Report report;
    report.set("command", "solve");
    const Scene scene = mpi_load_and_mesh(o.scene.scene, report);  // under mpirun: rank 0's, broadcast
    // Under mpirun each rank solves its block of rows (docs/scaling.md).
    const std::unique_ptr<RowBlocks> blocks = mpi_row_blocks(scene, o.rows);
    so.blocks = blocks.get();
    validate(so);
    const RowOptions row_options = mpi_row_options(o.rows);

    // Rows: from the file, or hemicubes. The hemicube provider starts before this process makes a
    // GL context of its own (the picture's), so that its workers can be forked processes.
    std::optional<FfmFile> ffm;
    std::unique_ptr<MatrixRowProvider> matrix_rows;
    RowSource computed_rows;
    RowProvider* provider = nullptr;
    Stopwatch watch;
    if (!o.matrix.empty()) {
        ffm = read_ffm(o.matrix);
        check_ffm_matches(*ffm, scene);
        matrix_rows = std::make_unique<MatrixRowProvider>(ffm->matrix);
        provider = matrix_rows.get();
        report.set("rows", "matrix");
        report.set("matrix", o.matrix);
        report.set("time.reading_matrix", watch.seconds());
        info("rows from {} ({} non-zeros, {} {})", o.matrix, ffm->matrix.nnz(), ffm->meta.method, ffm->meta.settings);
    } else {
        computed_rows = make_row_source(scene, row_options);
        for (const std::string& line : describe(computed_rows)) info("{}", line);
        provider = &computed_rows.provider();
        report.set("rows", provider->name());
    }

    double last_print = 0.0;
    so.progress = [&](const SolveProgress& p) {
        if (p.seconds - last_print < 1.0) return;
        last_print = p.seconds;
        info("{}: {} {}, unshot {:.3e} of emitted, {:.1f} s", to_string(p.method), p.iterations,
             p.method == SolverMethod::Shoot ? "shots" : "sweeps", p.unshot_fraction, p.seconds);
    };
    const SolveResult res = solve_radiosity(scene, *provider, so);
    info("{}: {} after {} {} ({} rows computed, {} reused), unshot {:.3e}, {:.2f} s", to_string(res.method),
         to_string(res.stop), res.iterations, res.method == SolverMethod::Shoot ? "shots" : "sweeps",
         res.cache.rows_computed, res.cache.rows_reused, res.unshot_fraction, res.timings.total);
    if (res.stiffness.action != "none")
        info("stiff scene: {} after {} shots ({} products with the rows): {}", res.stiffness.action,
             res.stiffness.switched_at_shot, res.stiffness.krylov_products, res.stiffness.reason);
    report_result(report, res, so, scene.size());
    if (o.matrix.empty()) {
        report_row_source(report, computed_rows);
        computed_rows = RowSource{};  // its workers are done
    }
    if (!mpi_root()) return 0;  // every rank has B; rank 0 writes
    if (!res.converged()) {  // exit 5 and only the report, unless --allow-unconverged (docs/solve.md)
        if (!o.report.empty() && (!o.allow_unconverged || res.stop == StopReason::Diverged)) report.write(o.report);
        require_converged(res, so, o.allow_unconverged);
        warn("{}; writing the results anyway (--allow-unconverged; the report says \"converged\": false)",
             describe_unconverged(res, so));
    }

    // What pictures and meshes show (render/solved_scene.hpp).
    const std::vector<Vec3> radiance = patch_radiance(res.radiosity);
    const bool exposure_given = o.exposure_option && o.exposure_option->count() > 0;
    const double exposure = scene_exposure(scene, radiance, exposure_given ? std::optional(o.exposure) : std::nullopt);
    const Shading shading = o.flat ? Shading::Flat : Shading::Smooth;

    std::optional<Image> image;
    if (!o.render.empty()) {
        watch.restart();
        RenderSettings rs;
        rs.width = o.width;
        rs.height = o.height;
        rs.flat = o.flat;
        rs.camera = camera ? *camera : default_camera(scene);
        rs.back_face_value = Vec3(0.02 / exposure);  // shows as a dark grey (2% linear) in the PNG
        const std::unique_ptr<GlContext> ctx = create_headless_context(o.rows.backend);
        image = render_mesh(*ctx, shade_patches(scene, radiance, shading), rs);
        report.set("render.path", o.render);
        report.set("render.width", rs.width);
        report.set("render.height", rs.height);
        report.set("render.shading", o.flat ? "flat" : "smooth");
        report_vec3(report, "render.camera.eye", rs.camera.eye);
        report_vec3(report, "render.camera.target", rs.camera.target);
        report.set("render.camera.fov_degrees", rs.camera.fov_degrees);
        report.set("render.backend", ctx->backend());
        report.set("render.renderer", ctx->renderer());
        report.set("time.render", watch.seconds());
    }
    report.set("exposure", exposure);
    report.set("exposure_automatic", !exposure_given);

    // Every result is computed; now the files, each atomically.
    watch.restart();
    if (!o.objects.empty()) {
        const std::vector<ObjectRadiosity> objs = object_radiosity(scene, res.radiosity);
        std::vector<std::string> names;
        std::vector<double> areas;
        std::vector<Vec3> B;
        for (const ObjectRadiosity& ob : objs) {
            names.push_back(ob.name);
            areas.push_back(ob.area);
            B.push_back(ob.radiosity);
        }
        write_object_radiosity_csv(o.objects, names, areas, B);
    }
    if (!o.radiosity.empty()) {
        std::vector<std::uint32_t> object(scene.size());
        std::vector<double> area(scene.size());
        for (std::size_t i = 0; i < scene.size(); ++i) {
            object[i] = scene.patches[i].object;
            area[i] = scene.patches[i].area;
        }
        write_patch_radiosity_csv(o.radiosity, object, area, res.radiosity, scene.objects);
    }
    if (!o.mesh.empty()) {
        write_ply(o.mesh, solved_ply_mesh(scene, res.radiosity, shading, exposure),
                  fmt::format("ffcube solve of {}: colours = sRGB of exposure {:.6g} x radiosity / pi; radiosity_* = B", scene.source,
                              exposure));
    }
    if (image) {
        if (exr)
            write_exr(o.render, *image);
        else
            write_png(o.render, *image, exposure);
    }
    report.set("time.writing", watch.seconds());
    report.set("time.total", total.seconds());
    if (!o.report.empty()) report.write(o.report);
    return 0;
}

}  // namespace

void add_solve_command(CLI::App& app, std::function<int()>& action) {
    auto opts = std::make_shared<Options>();
    CLI::App* sub = app.add_subcommand("solve", "solve the radiosity of a scene; write CSV, report, picture, mesh");
    add_scene_options(*sub, opts->scene);
    add_row_options(*sub, opts->rows);
    sub->add_option("--solver", opts->solver, "shoot (progressive refinement), jacobi, gauss-seidel or direct")
        ->check(CLI::IsMember({"shoot", "jacobi", "gauss-seidel", "direct"}))
        ->default_val("shoot");
    sub->add_option("--tolerance", opts->tolerance, "stop when unshot power <= tolerance x emitted power")->default_val(1e-4);
    sub->add_option("--max-iterations", opts->max_iterations, "most shots (shoot) or sweeps (default: the method's own)");
    opts->overshoot_option =
        sub->add_option("--overshoot", "over-relax shooting by the factor in [1,2) (alone: 1.2)")->expected(0, 1);
    sub->add_option("--row-cache-mb", opts->row_cache_mb, "bound of the cache of shooters' rows, MiB (0: none)")->default_val(512);
    sub->add_option("--matrix", opts->matrix, "take the rows from F.ffm (from `ffcube formfactors`) instead of hemicubes");
    sub->add_option("--objects", opts->objects, "write area-weighted mean radiosity per object (object,area,B_r,B_g,B_b)");
    sub->add_option("--radiosity", opts->radiosity, "write radiosity per patch (patch,object,area,B_r,B_g,B_b)");
    sub->add_option("--report", opts->report, "write a JSON report (convergence, energy, row cache, timings)");
    sub->add_option("--render", opts->render, "write a picture: IMG.exr (linear radiance B/pi) or IMG.png (tone-mapped sRGB)");
    sub->add_option("--camera", opts->camera, "ex,ey,ez,tx,ty,tz[,fov]: eye, target, vertical field of view in degrees");
    sub->add_option("--width", opts->width, "picture width in pixels")->default_val(512);
    sub->add_option("--height", opts->height, "picture height in pixels")->default_val(512);
    sub->add_flag("--flat", opts->flat, "one value per patch (default: smooth, patch values interpolated to vertices)");
    opts->exposure_option =
        sub->add_option("--exposure", opts->exposure, "PNG and PLY colours: display value = exposure x radiance (default: automatic)");
    sub->add_option("--mesh", opts->mesh, "write the solved mesh with per-vertex colours as OUT.ply");
    sub->add_flag("--allow-unconverged", opts->allow_unconverged,
                  "write the results of a solve that stopped before its tolerance (else exit 5, report only)");
    sub->callback([opts, &action] {
        action = [opts] {
            if (opts->scene.quiet) set_log_level(LogLevel::Quiet);
            return run(*opts);
        };
    });
}

}  // namespace ffcube::cli
