// ffcube radiate: gray-body radiative exchange (temperatures and emissivities in; net heat flux,
// solved temperatures and Gebhart conductances out) on the rows of F, computed once or read from a
// .ffm file. docs/radiate.md; the library is solver/radiate.hpp.
#include <fmt/format.h>

#include <cmath>
#include <memory>
#include <optional>

#include "cli/commands.hpp"
#include "cli/common.hpp"
#include "cli/expert.hpp"
#include "cli/mpi_glue.hpp"
#include "ffcube/core/error.hpp"
#include "ffcube/core/input_file.hpp"
#include "ffcube/core/log.hpp"
#include "ffcube/core/timer.hpp"
#include "ffcube/io/atomic_file.hpp"
#include "ffcube/io/csv.hpp"
#include "ffcube/io/ffm.hpp"
#include "ffcube/io/ply.hpp"
#include "ffcube/io/fields.hpp"
#include "ffcube/io/report.hpp"
#include "ffcube/pipeline/form_factors.hpp"
#include "ffcube/pipeline/row_source.hpp"
#include "ffcube/pipeline/scene_loading.hpp"
#include "ffcube/render/shading.hpp"
#include "ffcube/solver/radiate.hpp"

namespace ffcube::cli {
namespace {

// The name of the pseudo-object that stands for the sky in --conductances.
constexpr const char* kSkyNode = "(sky)";

struct Options {
    SceneFlags scene;
    RowOptions rows;
    std::string surfaces, bands, matrix, out, patch_out, conductances, default_surface, report, mesh, fields;
    double sky_temperature = 0.0;
    CLI::Option* sky_option = nullptr;
    double conductance_threshold = 1e-6;
    double tolerance = 1e-10;
    std::uint64_t max_iterations = 5000;
    std::uint32_t restart = 60;
    double open_threshold = 1e-6;
    double outer_tolerance = 1e-8;
    std::uint32_t max_outer_iterations = 50;
    bool stream_matrix = false;
};

// F's rows read block by block from a version-2 .ffm at every product (--stream-matrix): memory
// bounded by one block, one pass over the file per product. Row i's sum is taken in column order
// as CsrRowProduct does, so the results are the same bits as with F in memory.
class StreamedRows final : public RowProduct {
public:
    explicit StreamedRows(const std::string& path) : reader_(path) {}
    const FfmHead& head() const { return reader_.head(); }
    std::uint32_t size() const override { return reader_.head().n; }
    void multiply(std::span<const double> x, std::span<double> y) const override {
        each_row([&](std::uint32_t i, RowView r) {
            double s = 0.0;
            for (std::size_t k = 0; k < r.col.size(); ++k) s += double(r.val[k]) * x[r.col[k]];
            y[i] = s;
        });
    }
    std::vector<double> row_sums() const override {
        std::vector<double> s(size());
        each_row([&](std::uint32_t i, RowView r) { s[i] = r.sum(); });
        return s;
    }
    std::uint64_t passes() const { return passes_; }

private:
    template <class F>
    void each_row(F&& f) const {
        reader_.rewind();
        while (reader_.next(block_))
            for (std::uint32_t k = 0; k < block_.rows; ++k) f(block_.first_row + k, block_.row(k));
        ++passes_;
    }
    mutable FfmReader reader_;
    mutable FfmBlock block_;
    mutable std::uint64_t passes_ = 0;
};

std::string num(double v) { return fmt::format("{:.10g}", v); }

struct ObjectTotals {
    double area = 0.0, power = 0.0, t4 = 0.0;  // Σ A, Σ A q, Σ A T⁴
};

void write_objects(const std::string& path, const Scene& scene, std::span<const SurfaceSpec> spec,
                   const RadiateResult& r) {
    std::vector<ObjectTotals> t(scene.objects.size());
    for (std::size_t i = 0; i < scene.size(); ++i) {
        const Patch& p = scene.patches[i];
        ObjectTotals& o = t[p.object];
        o.area += p.area;
        o.power += p.area * r.heat_flux[i];
        o.t4 += p.area * std::pow(r.temperature[i], 4);
    }
    write_file_atomically(path, [&](std::ostream& os) {
        os << "object,area,emissivity,temperature,heat_flux,power\n";
        for (std::size_t k = 0; k < t.size(); ++k) {
            const ObjectTotals& o = t[k];
            // A given temperature is echoed; a solved one is the area-weighted mean of T⁴, to the ¼
            // (the temperature of a uniform surface that emits the same power: docs/radiate.md).
            std::string temperature;
            if (spec[k].condition == SurfaceCondition::Temperature)
                temperature = num(spec[k].value);
            else if (o.area > 0.0)
                temperature = num(std::pow(o.t4 / o.area, 0.25));
            os << csv_field(scene.objects[k]) << ',' << num(o.area) << ',' << num(spec[k].emissivity) << ','
               << temperature << ',' << (o.area > 0.0 ? num(o.power / o.area) : "0") << ',' << num(o.power) << '\n';
        }
    });
}

// A mesh read through Gmsh or meshio adds the element each patch comes from (Scene::patch_elements).
void write_patches(const std::string& path, const Scene& scene, const RadiateResult& r) {
    const bool ids = scene.patch_elements.size() == scene.size();
    write_file_atomically(path, [&](std::ostream& os) {
        os << "patch,object,area,temperature,heat_flux,radiosity,irradiation" << (ids ? ",element_id\n" : "\n");
        for (std::size_t i = 0; i < scene.size(); ++i) {
            const Patch& p = scene.patches[i];
            os << i << ',' << csv_field(scene.objects[p.object]) << ',' << num(p.area) << ',' << num(r.temperature[i])
               << ',' << num(r.heat_flux[i]) << ',' << num(r.radiosity[i]) << ',' << num(r.irradiation[i]);
            if (ids) os << ',' << scene.patch_elements[i];
            os << '\n';
        }
    });
}

// The mesh coloured by net heat flux, one flat colour per patch: white at 0, to red at the largest
// flux leaving (+qmax) and to blue at the largest flux arriving (−qmax), linear in q; the PLY's
// comment gives qmax. Returns qmax.
double write_heat_flux_mesh(const std::string& path, const Scene& scene, const RadiateResult& r) {
    double qmax = 0.0;
    for (const double q : r.heat_flux) qmax = std::max(qmax, std::abs(q));
    std::vector<Vec3> values(scene.size());
    for (std::size_t i = 0; i < scene.size(); ++i) values[i] = Vec3(r.heat_flux[i]);
    const ShadedMesh shaded = shade_patches(scene, values, Shading::Flat);
    PlyMesh ply;
    ply.positions = shaded.positions;
    for (Vec3& x : ply.positions) x += scene.origin;
    for (const Vec3& v : shaded.values) {
        const double t = qmax > 0.0 ? std::clamp(v.r / qmax, -1.0, 1.0) : 0.0;
        const auto fade = static_cast<std::uint8_t>(std::lround(255.0 * (1.0 - std::abs(t))));
        ply.colors.push_back(t >= 0.0 ? std::array<std::uint8_t, 3>{255, fade, fade} : std::array<std::uint8_t, 3>{fade, fade, 255});
    }
    ply.face_sizes = shaded.face_sizes;
    ply.face_indices = shaded.face_indices;
    write_ply(path, ply,
              fmt::format("ffcube radiate: net heat flux leaving, white 0, red +{:.6g} W/m^2, blue -{:.6g} W/m^2", qmax, qmax));
    return qmax;
}

// One line per pair of objects (scene order, from < to), GR the mean of GR_kl and GR_lk (equal for
// reciprocal rows; the report gives their largest difference), and one per object to the sky;
// couplings below threshold × the largest are dropped. Returns {written, dropped}.
std::pair<std::size_t, std::size_t> write_conductances(const std::string& path, const Scene& scene,
                                                       const ConductanceResult& g, double threshold) {
    struct Line {
        std::size_t from;
        std::string to;
        double gr;
    };
    std::vector<Line> lines;
    const std::size_t k_count = scene.objects.size();
    for (std::size_t k = 0; k < k_count; ++k) {
        for (std::size_t l = k + 1; l < k_count; ++l) lines.push_back({k, scene.objects[l], 0.5 * (g.gr[k][l] + g.gr[l][k])});
        lines.push_back({k, kSkyNode, g.gr_sky[k]});
    }
    double largest = 0.0;
    for (const Line& x : lines) largest = std::max(largest, x.gr);
    std::size_t written = 0, dropped = 0;
    write_file_atomically(path, [&](std::ostream& os) {
        os << "from,to,GR\n";
        for (const Line& x : lines) {
            if (!(x.gr > 0.0) || x.gr < threshold * largest) {
                ++dropped;
                continue;
            }
            os << csv_field(scene.objects[x.from]) << ',' << csv_field(x.to) << ',' << num(x.gr) << '\n';
            ++written;
        }
    });
    return {written, dropped};
}

int run(const Options& o) {
    // Everything that can be refused is refused before any work.
    Stopwatch total;
    for (const auto& [option, path] : {std::pair{"-o", &o.out}, {"--patch-out", &o.patch_out},
                                       {"--conductances", &o.conductances}, {"--report", &o.report},
                                       {"--mesh", &o.mesh}, {"--fields", &o.fields}})
        check_output_path(option, *path);
    if (!o.mesh.empty() && !o.mesh.ends_with(".ply"))
        throw InputError(fmt::format("--mesh {}: the name must end in .ply", o.mesh));
    check_fields_path("--fields", o.fields);
    if (!(o.conductance_threshold >= 0.0 && o.conductance_threshold < 1.0))
        throw InputError(fmt::format("--conductance-threshold {}: must be in [0, 1)", o.conductance_threshold));
    if (mpi_distributed()) throw InputError("ffcube radiate runs in one process; run it without mpirun");
    RadiateOptions ro;
    if (o.sky_option && o.sky_option->count() > 0) ro.sky_temperature = o.sky_temperature;
    ro.tolerance = o.tolerance;
    ro.max_iterations = o.max_iterations;
    ro.restart = o.restart;
    ro.open_threshold = o.open_threshold;
    ro.outer_tolerance = o.outer_tolerance;
    ro.threads = o.rows.threads;  // --threads: the rows and the products with them
    ro.max_outer_iterations = o.max_outer_iterations;
    if (!(o.outer_tolerance > 0.0 && o.outer_tolerance < 1.0))
        throw InputError(fmt::format("--outer-tolerance {}: must be in (0, 1)", o.outer_tolerance));
    if (o.max_outer_iterations < 1) throw InputError("--max-outer-iterations: must be >= 1");
    if (o.stream_matrix && o.matrix.empty())
        throw InputError("--stream-matrix needs --matrix F.ffm (a version-2 file, as `ffcube formfactors -o F.ffm` writes)");
    if (!o.bands.empty() && !o.conductances.empty())
        throw InputError("--conductances with --bands: the conductances of non-gray surfaces depend on the temperatures; "
                         "they are computed for gray surfaces only (leave out --bands)");
    validate(ro);
    validate(o.rows);
    const std::vector<NamedSurface> lines =
        parse_surfaces_csv(read_input_file(o.surfaces, "a CSV file", "the surfaces"), o.surfaces);
    std::optional<SurfaceSpec> fallback;
    if (!o.default_surface.empty()) fallback = parse_default_surface(o.default_surface);
    std::vector<NamedBand> band_lines;
    if (!o.bands.empty()) band_lines = parse_bands_csv(read_input_file(o.bands, "a CSV file", "the bands"), o.bands);

    Report report;
    report.set("command", "radiate");
    Stopwatch watch;
    const Scene scene = load_and_mesh(o.scene.scene, report);
    report.set("time.loading", watch.seconds());
    if (scene.drawn)
        throw InputError(fmt::format("{}: has obstruction-only surfaces (View3D's O); radiate needs every surface to "
                                     "take part in the exchange: give them an emissivity as ordinary surfaces",
                                     scene.source));
    const std::vector<SurfaceSpec> object_spec = surfaces_for_objects(scene.objects, lines, o.surfaces, fallback);
    report.set("surfaces", o.surfaces);
    std::optional<BandModel> bands;
    if (!o.bands.empty()) {
        std::vector<double> gray(object_spec.size());
        for (std::size_t k = 0; k < gray.size(); ++k) gray[k] = object_spec[k].emissivity;
        bands = bands_for_objects(scene.objects, band_lines, o.bands, gray);
        report.set("bands", o.bands);
    }
    report.set("patches", scene.size());
    report.set("objects", scene.objects.size());

    // Rows: once, into a CsrMatrix (from the file, checked against the scene, or computed).
    watch.restart();
    CsrMatrix F;
    std::optional<FormFactorFigures> computed;  // F computed here: its figures
    std::unique_ptr<StreamedRows> streamed;
    if (o.stream_matrix) {
        streamed = std::make_unique<StreamedRows>(o.matrix);
        check_ffm_matches(streamed->head(), scene);
        report.set("rows", "matrix, streamed");
        report.set("matrix", o.matrix);
    } else if (!o.matrix.empty()) {
        FfmFile ffm = read_ffm(o.matrix);
        check_ffm_matches(ffm, scene);
        F = std::move(ffm.matrix);
        report.set("rows", "matrix");
        report.set("matrix", o.matrix);
    } else {
        RowSource rows = make_row_source(scene, resolve_row_method(o.rows, scene.drawn_scene()));
        for (const std::string& line : describe(rows)) info("{}", line);
        report.set("rows", rows.provider().name());
        F = form_factor_matrix(scene, rows, report, {}, &computed.emplace());  // the one path, with its checks
        report_row_source(report, rows);
    }
    report.set("time.rows", watch.seconds());
    watch.restart();
    if (streamed) {  // row sums only: reciprocity needs F's transpose
        const std::vector<double> sums = streamed->row_sums();
        double lo = 1e300, hi = -1e300, mean = 0.0;
        for (const double x : sums) {
            lo = std::min(lo, x);
            hi = std::max(hi, x);
            mean += x;
        }
        report.set("row_sums.min", sums.empty() ? 0.0 : lo);
        report.set("row_sums.max", sums.empty() ? 0.0 : hi);
        report.set("row_sums.mean", sums.empty() ? 0.0 : mean / double(sums.size()));
    } else if (computed) {  // checked while the rows came (pipeline/form_factors.hpp)
        report_matrix_stats(report, computed->nnz, computed->row_sums, computed->reciprocity);
    } else {
        report_matrix_checks(report, F, scene, false);  // row sums and reciprocity: a transpose of F
    }
    report.set("time.matrix_checks", watch.seconds());
    const CsrRowProduct in_memory(F, ro.threads);
    const RowProduct& rows_of_f = streamed ? static_cast<const RowProduct&>(*streamed) : in_memory;

    std::vector<double> area(scene.size()), emissivity(scene.size());
    std::vector<std::uint32_t> object(scene.size());
    std::vector<SurfaceSpec> spec(scene.size());
    for (std::size_t i = 0; i < scene.size(); ++i) {
        const Patch& p = scene.patches[i];
        area[i] = p.area;
        object[i] = p.object;
        spec[i] = object_spec[p.object];
        emissivity[i] = spec[i].emissivity;
    }
    ro.patch_name = [&scene](std::uint32_t i) {
        return fmt::format("patch {} of object '{}'", i, scene.objects[scene.patches[i].object]);
    };
    report.set("solver.method", fmt::format("gmres({})", ro.restart));
    report.set("solver.tolerance", ro.tolerance);
    const auto refuse = [&](const NotConvergedError& e) {  // the report says why; no result file
        report.set("converged", false);
        report.set("error", e.what());
        if (!o.report.empty()) report.write(o.report);
    };
    watch.restart();
    RadiateResult r;
    try {
        r = bands ? solve_radiation_bands(rows_of_f, area, spec, object, *bands, ro) : solve_radiation(rows_of_f, area, spec, ro);
    } catch (const NotConvergedError& e) {
        refuse(e);
        throw;
    }
    report.set("time.solve", watch.seconds());
    report.set("converged", true);
    report.set("solver.iterations", r.iterations);
    report.set("solver.residual", r.residual);
    report.set("solver.min_emissivity", r.min_emissivity);
    report.set("solver.bands", r.bands);
    if (bands) {
        report.set("solver.outer_iterations", r.outer_iterations);
        report.set("solver.outer_residual", r.outer_residual);
    }
    double sky_area = 0.0, total_area = 0.0, sky_max = 0.0;
    for (std::size_t i = 0; i < scene.size(); ++i) {
        sky_area += area[i] * r.sky_view[i];
        total_area += area[i];
        sky_max = std::max(sky_max, r.sky_view[i]);
    }
    if (ro.sky_temperature) report.set("sky.temperature", *ro.sky_temperature);
    report.set("sky.view_factor_mean", total_area > 0.0 ? sky_area / total_area : 0.0);
    report.set("sky.view_factor_max", sky_max);
    report.set("energy.power", r.power);
    report.set("energy.sky", r.sky);
    report.set("energy.absolute_power", r.absolute_power);
    report.set("energy.relative_error", r.balance_error);
    info("radiate: {} patches, GMRES {} products, residual {:.3g}; net power {:.6g} W, to the sky {:.6g} W (balance error {:.3g})",
         scene.size(), r.iterations, r.residual, r.power, r.sky, r.balance_error);

    std::optional<ConductanceResult> g;
    if (!o.conductances.empty()) {
        watch.restart();
        try {
            g = radiative_conductances(rows_of_f, area, emissivity, object, static_cast<std::uint32_t>(scene.objects.size()), ro);
        } catch (const NotConvergedError& e) {
            refuse(e);
            throw;
        }
        report.set("time.conductances", watch.seconds());
        report.set("conductances.solves", g->solves);
        report.set("conductances.iterations", g->iterations);
        report.set("conductances.max_residual", g->max_residual);
        report.set("conductances.reciprocity_error", g->reciprocity_error);
        report.set("conductances.sum_rule_error", g->sum_rule_error);
        report.set("conductances.threshold", o.conductance_threshold);
        info("conductances: {} solves, {} products; reciprocity error {:.3g}, sum rule error {:.3g}", g->solves,
             g->iterations, g->reciprocity_error, g->sum_rule_error);
    }

    if (streamed) report.set("matrix_passes", streamed->passes());
    // Every result is computed and converged; now the files, each atomically.
    watch.restart();
    if (!o.out.empty()) write_objects(o.out, scene, object_spec, r);
    if (!o.patch_out.empty()) write_patches(o.patch_out, scene, r);
    if (!o.mesh.empty()) report.set("mesh.heat_flux_max", write_heat_flux_mesh(o.mesh, scene, r));
    if (!o.fields.empty()) {
        write_fields(o.fields, scene,
                         {{"temperature", r.temperature}, {"heat_flux", r.heat_flux}, {"radiosity", r.radiosity},
                          {"irradiation", r.irradiation}, {"sky_view_factor", r.sky_view}});
        report.set("fields.written", o.fields);
    }
    if (g) {
        const auto [written, dropped] = write_conductances(o.conductances, scene, *g, o.conductance_threshold);
        report.set("conductances.written", written);
        report.set("conductances.dropped", dropped);
    }
    report.set("time.writing", watch.seconds());
    report.set("time.total", total.seconds());
    if (!o.report.empty()) report.write(o.report);
    return 0;
}

}  // namespace

void add_radiate_command(CLI::App& app, std::function<int()>& action) {
    auto opts = std::make_shared<Options>();
    CLI::App* sub = app.add_subcommand(
        "radiate", "gray-body radiative exchange: temperatures and emissivities in; heat flux, temperatures, conductances out");
    add_scene_options(*sub, opts->scene);
    add_row_options(*sub, opts->rows, RowTolerance::expert);
    sub->add_option("--surfaces", opts->surfaces, "CSV object,emissivity,temperature,heat_flux (one of the last two per line)")
        ->required();
    opts->sky_option = sub->add_option("--sky-temperature", opts->sky_temperature,
                                       "K: what the openings of an open scene see (required when the scene is open)");
    sub->add_option("--default-surface", opts->default_surface, "EMISSIVITY,TEMPERATURE for objects the CSV does not list");
    sub->add_option("--bands", opts->bands,
                    "CSV object,lambda_min_um,lambda_max_um,emissivity: non-gray surfaces by spectral bands");
    sub->add_option("--matrix", opts->matrix, "take F from F.ffm (from `ffcube formfactors`) instead of computing it");
    sub->add_option("-o,--out", opts->out, "write per object: object,area,emissivity,temperature,heat_flux,power");
    sub->add_option("--patch-out", opts->patch_out,
                    "write per patch: patch,object,area,temperature,heat_flux,radiosity,irradiation");
    sub->add_option("--mesh", opts->mesh, "write the mesh coloured by net heat flux as OUT.ply (white 0, red out, blue in)");
    sub->add_option("--conductances", opts->conductances, "write Gebhart conductances between objects: from,to,GR (m^2)");
    expert(sub->add_option("--fields", opts->fields,
                           "write the meshed scene with per-patch temperature, heat_flux, radiosity, irradiation, "
                           "sky_view_factor (and element_id): OUT.vtu for ParaView, or OUT.msh, a Gmsh model with views "
                           "(docs/fe-meshes.md)"));
    sub->add_option("--report", opts->report, "write a JSON report (energy balance, solver, timings)");
    expert(sub->add_option("--conductance-threshold", opts->conductance_threshold,
                           "drop conductances below this fraction of the largest")
               ->default_val(1e-6));
    expert(sub->add_option("--tolerance", opts->tolerance, "GMRES: relative residual to reach")->default_val(1e-10));
    expert(sub->add_option("--max-iterations", opts->max_iterations, "GMRES: most products with the rows per solve")
               ->default_val(5000));
    expert(sub->add_option("--gmres-restart", opts->restart, "GMRES: Krylov vectors per cycle")->default_val(60));
    expert(sub->add_option("--open-threshold", opts->open_threshold,
                           "a patch whose sky view factor exceeds this makes the scene open")
               ->default_val(1e-6));
    expert(sub->add_flag("--stream-matrix", opts->stream_matrix,
                         "with --matrix: read F block by block at every product instead of holding it (memory: one "
                         "block; time: one pass over the file per product; the same results)"));
    expert(sub->add_option("--outer-tolerance", opts->outer_tolerance,
                           "--bands: heat-flux residual, relative to the largest emissive power, of the temperature iteration")
               ->default_val(1e-8));
    expert(sub->add_option("--max-outer-iterations", opts->max_outer_iterations,
                           "--bands: most outer iterations for the temperatures of heat-flux surfaces")
               ->default_val(50));
    sub->callback([opts, &action] {
        action = [opts] {
            if (opts->scene.quiet) set_log_level(LogLevel::Quiet);
            return run(*opts);
        };
    });
}

}  // namespace ffcube::cli
