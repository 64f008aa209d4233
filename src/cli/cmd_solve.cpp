// ffcube solve: radiosity of a scene (rows from hemicubes or from a .ffm file), with its results
// as CSV, a JSON report, a picture (EXR or PNG) and a coloured mesh (PLY). docs/solve.md.
#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <memory>
#include <cmath>
#include <numbers>
#include <optional>

#include "cli/commands.hpp"
#include "cli/common.hpp"
#include "cli/expert.hpp"
#include "cli/mpi_glue.hpp"
#include "cli/surface_options.hpp"
#include "ffcube/core/error.hpp"
#include "ffcube/core/log.hpp"
#include "ffcube/core/progress.hpp"
#include "ffcube/core/timer.hpp"
#include "ffcube/formfactor/sky.hpp"
#include "ffcube/io/csv.hpp"
#include "ffcube/io/ffm.hpp"
#include "ffcube/io/fields.hpp"
#include "ffcube/io/ply.hpp"
#include "ffcube/pipeline/adaptive.hpp"
#include "ffcube/pipeline/row_source.hpp"
#include "ffcube/pipeline/scene_loading.hpp"
#include "ffcube/pipeline/solve.hpp"
#include "ffcube/pipeline/surface_outputs.hpp"
#include "ffcube/render/renderer.hpp"
#include "ffcube/render/solved_scene.hpp"
#include "ffcube/solver/solver.hpp"

namespace ffcube::cli {
namespace {

struct Options {
    SceneFlags scene;
    RowOptions rows;
    std::string solver = "shoot";
    double tolerance = 1e-4;
    std::uint64_t max_iterations = 0;
    CLI::Option* overshoot_option = nullptr;  // unbound: 0 or 1 values, parsed in run()
    double row_cache_mb = 512.0;
    std::string matrix, objects, radiosity, report, render, mesh, camera, fields;
    int width = 512, height = 512;
    bool flat = false;
    double exposure = 0.0;  // 0: automatic
    CLI::Option* exposure_option = nullptr;
    bool allow_unconverged = false;
    // Adaptive meshing (docs/adaptive.md): on when either is given.
    AdaptiveFlags adaptive;
    SurfaceOutputOptions sky;  // --sky, --sky-by only (add_sky_options)
};

// The solve's provider, passed through, keeping the sum of each row it hands on: the rows the
// solve shoots, for the sky view factors (--sky), which then compute only the rows not shot.
// Sums as stored (SparseRow::stored_sum: RowView::sum of the rows compute_form_factors hands on, bit for bit).
class RowSumKeeper final : public ObservingRowProvider {
public:
    explicit RowSumKeeper(RowProvider& inner) : ObservingRowProvider(inner), sums_(inner.size(), NAN) {}
    // Per row: its stored sum, or NaN for a row not handed on.
    std::vector<double>& sums() { return sums_; }

private:
    const SparseRow& observe(std::uint32_t i, const SparseRow& row) override {
        sums_[i] = row.stored_sum();
        return row;
    }
    std::vector<double> sums_;
};

// Each row's sum for the sky view factors (--sky), as `ffcube formfactors` takes them: every row
// of F, not only the shooters' (the solve asks only for those). `known` holds the sums of the
// rows the solve already had (NaN for the others; empty: none); only the rest are computed,
// through the solve's own provider, so the rows are those formfactors computes for the same
// options (a provider's row does not depend on which rows are asked with it). Returns how many
// were reused.
std::size_t sky_row_sums(RowProvider& provider, std::vector<double>& sums, bool progress) {
    const std::uint32_t n = provider.size();
    sums.resize(n, NAN);
    std::vector<std::uint32_t> missing;
    for (std::uint32_t i = 0; i < n; ++i)
        if (std::isnan(sums[i])) missing.push_back(i);
    if (missing.empty()) return n;
    Progress bar("sky rows", missing.size(), progress);
    provider.compute_rows(missing, [&](std::uint32_t i, const SparseRow& row) {
        sums[i] = row.stored_sum();
        bar.add();
    });
    return n - missing.size();
}

// --fields: B per patch (one array per channel), and the sky view factors when --sky computed
// them (less what obstruction-only surfaces intercept, as --sky writes them).
void write_solve_fields(const std::string& path, const Scene& scene, std::span<const Vec3> radiosity, std::span<const double> sky_sums,
                        std::span<const double> obstructed, Report& report) {
    std::array<std::vector<double>, 3> b;
    for (int c = 0; c < 3; ++c) {
        b[std::size_t(c)].resize(scene.size());
        for (std::size_t i = 0; i < scene.size(); ++i) b[std::size_t(c)][i] = radiosity[i][c];
    }
    std::vector<CellField> fields{{"radiosity_r", b[0]}, {"radiosity_g", b[1]}, {"radiosity_b", b[2]}};
    std::vector<double> svf;
    if (!sky_sums.empty()) {
        svf = sky_view_factors(sky_sums);
        for (std::size_t i = 0; i < obstructed.size() && i < svf.size(); ++i) svf[i] = std::max(0.0, svf[i] - obstructed[i]);
        fields.push_back({"sky_view_factor", svf});
    }
    write_fields(path, scene, fields);
    report.set("fields.written", path);
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
        so.overshoot = parse_overshoot(given.empty() ? "" : given.back());
    }
    so.row_cache_mb = o.row_cache_mb;
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
                                       {"--report", &o.report}, {"--render", &o.render}, {"--mesh", &o.mesh}, {"--fields", &o.fields}})
        check_output_path(option, *path);
    check_fields_path("--fields", o.fields);
    check_surface_output_paths(o.sky);
    if (!o.sky.sky.empty() && mpi_distributed())
        throw InputError("--sky under mpirun: ffcube solve's ranks hold only their block of rows; use `mpirun ... ffcube "
                         "formfactors --sky` (the same file)");
    validate(o.rows);
    std::optional<Camera> camera;
    if (!o.camera.empty()) camera = parse_camera(o.camera);

    const bool adaptive = o.adaptive.on();
    SceneOptions scene_options = o.scene.scene;
    prepare_adaptive(o.adaptive, scene_options);
    if (adaptive) {
        if (!o.matrix.empty()) throw InputError("--matrix with --target-error/--max-elements: adaptive meshing computes the rows of the elements it makes");
        if (mpi_distributed()) throw InputError("--target-error/--max-elements under mpirun: adaptive meshing runs in one process (docs/scaling.md)");
    }

    Stopwatch total;
    Report report;
    report.set("command", "solve");
    Scene scene = mpi_load_and_mesh(scene_options, report);  // under mpirun: rank 0's, broadcast
    if (!o.sky.sky.empty() && !o.matrix.empty() && scene.drawn)
        throw InputError(fmt::format("--sky with --matrix: {} has obstruction-only surfaces, and a .ffm does not record the "
                                     "share of each row they intercept; run without --matrix, or `ffcube formfactors --sky`",
                                     scene.source));
    // Under mpirun each rank solves its block of rows (docs/scaling.md).
    // --method auto, resolved before the ranks' blocks are balanced by the rows' estimated cost.
    const RowOptions row_options = resolve_row_method(mpi_row_options(o.rows), scene.drawn_scene());
    const std::unique_ptr<RowBlocks> blocks = mpi_row_blocks(scene, row_options);
    so.blocks = blocks.get();
    validate(so);

    // Rows: from the file, or hemicubes. The hemicube provider starts before this process makes a
    // GL context of its own (the picture's), so that its workers can be forked processes.
    std::optional<FfmFile> ffm;
    std::unique_ptr<MatrixRowProvider> matrix_rows;
    RowSource computed_rows;
    RowProvider* provider = nullptr;
    Stopwatch watch;
    if (!o.matrix.empty()) {
        info("reading {} (the whole matrix, then checked against the scene)", o.matrix);  // silent otherwise
        ffm = read_ffm(o.matrix);
        check_ffm_matches(*ffm, scene);
        matrix_rows = std::make_unique<MatrixRowProvider>(ffm->matrix);
        provider = matrix_rows.get();
        report.set("rows", "matrix");
        report.set("matrix", o.matrix);
        report.set("time.reading_matrix", watch.seconds());
        info("rows from {} ({} non-zeros, {} {})", o.matrix, ffm->matrix.nnz(), ffm->meta.method, ffm->meta.settings);
    } else if (!adaptive) {
        computed_rows = make_row_source(scene, row_options);
        for (const std::string& line : describe(computed_rows)) info("{}", line);
        provider = &computed_rows.provider();
        report.set("rows", provider->name());
    }

    std::optional<AdaptiveResult> refined;
    if (adaptive) {  // the levels' solves, each on its own rows; the rest runs on the last level's scene
        const SolverOptions level_options = front_end_solver_options(so);
        refined = solve_adaptive(scene, o.rows, level_options, o.adaptive.options,
                                 [](const std::string& line) { info("{}", line); });
        info("adaptive: {} ({} elements from {} patches), largest estimated object error {:.3g}", refined->stop,
             refined->scene->size(), scene.size(), refined->max_relative_error);
        for (const std::string& line : describe(refined->rows)) info("{}", line);
        report.set("rows", refined->rows.provider().name());
        report_adaptive(report, *refined, o.adaptive.options);
        scene = *refined->scene;  // a copy: the last level's rows refer to *refined->scene, which stays
        computed_rows = std::move(refined->rows);
        report_solve(scene, refined->result, level_options, report);
    }
    // With --sky, the rows the solve shoots keep their sums: the sky then computes only the others.
    std::optional<RowSumKeeper> keeper;
    if (!o.sky.sky.empty() && provider && !ffm) provider = &keeper.emplace(*provider);
    const SolveResult res = refined ? std::move(refined->result) : solve_and_report(scene, *provider, so, report);
    // Sky view factors need every row: computed now, while the row workers are up and before this
    // process makes a GL context of its own (the picture's). Not for a solve that stops at exit 5.
    std::vector<double> sky_sums;
    std::vector<double> obstructed;  // copied: it outlives computed_rows
    if (!o.sky.sky.empty() && mpi_root() && (res.converged() || o.allow_unconverged)) {
        watch.restart();
        if (ffm) {
            sky_sums.resize(scene.size());
            for (std::uint32_t i = 0; i < scene.size(); ++i) sky_sums[i] = ffm->matrix.row(i).sum();
        } else {
            if (keeper) sky_sums = std::move(keeper->sums());
            const std::size_t reused = sky_row_sums(computed_rows.provider(), sky_sums, !o.scene.quiet);
            report.set("sky.rows_reused", reused);
            report.set("sky.rows_computed", scene.size() - reused);
            info("sky: {} rows kept from the solve, {} computed", reused, scene.size() - reused);
            if (scene.drawn) {  // each row's share came with it (RowSide), noted in the source's ledger
                const std::span<const double> cut = computed_rows.ledger().obstructed();
                obstructed.assign(cut.begin(), cut.end());
            }
        }
        report.set("time.sky_rows", watch.seconds());
    }
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
    if (!o.objects.empty()) write_objects_csv(o.objects, scene, res.radiosity);
    if (!o.radiosity.empty()) {
        std::vector<std::uint32_t> object(scene.size());
        std::vector<double> area(scene.size());
        for (std::size_t i = 0; i < scene.size(); ++i) {
            object[i] = scene.patches[i].object;
            area[i] = scene.patches[i].area;
        }
        write_patch_radiosity_csv(o.radiosity, object, area, res.radiosity, scene.objects);
    }
    if (!o.sky.sky.empty()) write_sky_outputs(o.sky, sky_sums, scene, report, obstructed);
    if (!o.fields.empty()) write_solve_fields(o.fields, scene, res.radiosity, sky_sums, obstructed, report);
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
    add_row_options(*sub, opts->rows, RowTolerance::expert);
    add_far_field_emitters_option(*sub, opts->rows);
    sub->add_option("--solver", opts->solver, "shoot (progressive refinement), jacobi, gauss-seidel or direct")
        ->check(CLI::IsMember({"shoot", "jacobi", "gauss-seidel", "direct"}))
        ->default_val("shoot");
    sub->add_option("--tolerance", opts->tolerance, "stop when unshot power <= tolerance x emitted power")->default_val(1e-4);
    expert(sub->add_option("--max-iterations", opts->max_iterations, "most shots (shoot) or sweeps (default: the method's own)"));
    opts->overshoot_option =
        expert(sub->add_option("--overshoot", "over-relax shooting by the factor in [1,2) (alone: 1.2)")->expected(0, 1));
    expert(sub->add_option("--row-cache-mb", opts->row_cache_mb, "bound of the cache of shooters' rows, MiB (0: none)")->default_val(512));
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
    expert(sub->add_option("--fields", opts->fields,
                           "write the meshed scene with per-patch radiosity_r/g/b (and sky_view_factor with --sky, element_id): "
                           "OUT.vtu for ParaView, or OUT.msh, a Gmsh model with views (docs/fe-meshes.md)"));
    add_adaptive_options(*sub, opts->adaptive);
    add_sky_options(*sub, opts->sky);
    expert(sub->add_flag("--allow-unconverged", opts->allow_unconverged,
                         "write the results of a solve that stopped before its tolerance (else exit 5, report only)"));
    sub->callback([opts, &action] {
        action = [opts] {
            if (opts->scene.quiet) set_log_level(LogLevel::Quiet);
            return run(*opts);
        };
    });
}

}  // namespace ffcube::cli
