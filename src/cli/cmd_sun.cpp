// ffcube sun: the sunlit fraction of every patch (or object) for one sun direction, by shadow
// polygons (exact; --set sun-method=pixels: an orthographic item buffer along the sun; gl/sun.hpp;
// docs/urban.md, "Sun and shade"); with
// --sun-series, absorbed shortwave with reflections for every step (cli/sun_series.hpp).
#include <fmt/format.h>

#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <memory>
#include <string>
#include <vector>

#include "cli/commands.hpp"
#include "cli/common.hpp"
#include "cli/expert.hpp"
#include "cli/mpi_glue.hpp"
#include "cli/sun_series.hpp"
#include "ffcube/core/error.hpp"
#include "ffcube/core/log.hpp"
#include "ffcube/core/timer.hpp"
#include "ffcube/gl/sun.hpp"
#include "ffcube/io/atomic_file.hpp"
#include "ffcube/io/csv.hpp"
#include "ffcube/io/report.hpp"
#include "ffcube/pipeline/scene_loading.hpp"

namespace ffcube::cli {
namespace {

struct Options {
    SceneFlags scene;
    std::string direction, angles, out, by, report, backend = "auto", method = "clip";
    SunOptions sun;
    std::string series, albedo, matrix, sky_patches, sky_out;
    double reflection_tolerance = 1e-12;
    std::uint32_t batch = 32;
};

std::string num(double v) { return fmt::format("{:.10g}", v); }

// "a,b,c" → exactly `count` numbers (finite or not: the callers judge), InputError naming the option.
std::vector<double> parse_numbers(const std::string& text, std::size_t count, const char* option, const char* what) {
    std::vector<double> v;
    std::size_t b = 0;
    while (b <= text.size()) {
        const std::size_t e = std::min(text.find(',', b), text.size());
        const std::string word = text.substr(b, e - b);
        char* end = nullptr;
        errno = 0;
        const double x = word.empty() ? 0.0 : std::strtod(word.c_str(), &end);
        if (word.empty() || end != word.c_str() + word.size())
            throw InputError(fmt::format("{} {}: '{}' is not a number; expected {}", option, text, word, what));
        v.push_back(x);
        b = e + 1;
    }
    if (v.size() != count) throw InputError(fmt::format("{} {}: expected {} ({} numbers)", option, text, what, count));
    return v;
}

void write_patches(const std::string& path, const Scene& scene, const SunResult& r) {
    write_file_atomically(path, [&](std::ostream& os) {
        os << "patch,object,area,sunlit_fraction\n";
        for (std::size_t i = 0; i < scene.size(); ++i) {
            const Patch& p = scene.patches[i];
            os << i << ',' << csv_field(scene.objects[p.object]) << ',' << num(p.area) << ',' << num(r.fraction[i]) << '\n';
        }
    });
}

// Area-weighted: Σ A_i f_i / Σ A_i over the object's patches.
void write_objects(const std::string& path, const Scene& scene, const SunResult& r) {
    std::vector<double> area(scene.objects.size(), 0.0), lit(scene.objects.size(), 0.0);
    for (std::size_t i = 0; i < scene.size(); ++i) {
        const Patch& p = scene.patches[i];
        area[p.object] += p.area;
        lit[p.object] += p.area * r.fraction[i];
    }
    write_file_atomically(path, [&](std::ostream& os) {
        os << "object,area,sunlit_fraction\n";
        for (std::size_t k = 0; k < scene.objects.size(); ++k)
            os << csv_field(scene.objects[k]) << ',' << num(area[k]) << ',' << num(area[k] > 0.0 ? lit[k] / area[k] : 0.0)
               << '\n';
    });
}

int run(const Options& o) {
    Stopwatch total;
    // Everything that can be refused is refused before any work.
    check_output_path("-o", o.out);
    check_output_path("--report", o.report);
    if (o.by != "patch" && o.by != "object")
        throw InputError(fmt::format("--by {}: must be patch or object", o.by));
    if (!(o.sun.tolerance > 0.0 && o.sun.tolerance < 1.0))
        throw InputError(fmt::format("--tolerance {}: must be in (0, 1)", o.sun.tolerance));
    if (o.sun.max_pixels < 1) throw InputError("--max-pixels 0: must be at least 1");
    if (o.sun.tile < 0 || o.sun.tile == 1) throw InputError(fmt::format("--tile {}: must be 0 (automatic) or at least 2", o.sun.tile));
    if (o.method != "clip" && o.method != "pixels")
        throw InputError(fmt::format("--sun-method {}: must be clip (shadow polygons, exact) or pixels (the item buffer)", o.method));
    if (!o.series.empty()) {
        if (!o.direction.empty() || !o.angles.empty())
            throw InputError("--sun-series gives the sun of every step; leave out --sun and --sun-direction");
        if (mpi_distributed()) throw InputError("ffcube sun runs in one process; run it without mpirun");
        SunSeriesRequest q;
        q.scene = o.scene;
        q.series = o.series;
        q.albedo = o.albedo;
        q.matrix = o.matrix;
        q.sky_patches = o.sky_patches.empty() ? "isotropic" : o.sky_patches;
        q.sky_out = o.sky_out;
        q.out = o.out;
        q.by = o.by;
        q.report = o.report;
        q.sun = o.sun;
        q.sun.backend = parse_backend(o.backend);
        q.tolerance = o.reflection_tolerance;
        q.batch = o.batch;
        q.method = o.method;
        return run_sun_series(q);
    }
    for (const auto& [option, value] : {std::pair{"--albedo", &o.albedo}, {"--matrix", &o.matrix}, {"--sky-patches", &o.sky_patches},
                                               {"--sky-patches-out", &o.sky_out}})
        if (!value->empty()) throw InputError(fmt::format("{} goes with --sun-series (a series of sun positions)", option));
    if (o.direction.empty() == o.angles.empty())
        throw InputError("give the sun as exactly one of --sun-direction X,Y,Z (towards the sun) and --sun AZIMUTH,ELEVATION");
    Vec3 s;
    if (!o.direction.empty()) {
        const std::vector<double> v = parse_numbers(o.direction, 3, "--sun-direction", "X,Y,Z towards the sun");
        s = normalized_sun_direction(Vec3(v[0], v[1], v[2]), "--sun-direction");
    } else {
        const std::vector<double> v = parse_numbers(o.angles, 2, "--sun", "AZIMUTH,ELEVATION in degrees");
        s = sun_direction_from_angles(v[0], v[1]);
    }
    if (mpi_distributed()) throw InputError("ffcube sun runs in one process; run it without mpirun");
    SunOptions so = o.sun;
    so.backend = parse_backend(o.backend);

    Report report;
    report.set("command", "sun");
    Stopwatch watch;
    const Scene scene = load_and_mesh(o.scene.scene, report);
    report.set("time.loading", watch.seconds());
    const SunResult r = o.method == "clip" ? sunlit_fractions_clipped(scene, s) : sunlit_fractions(scene, s, so);
    if (o.method == "clip")
        info("sun ({:.6f}, {:.6f}, {:.6f}): {} of {} patches face it; shadow polygons (exact); {:.2f} s", r.sun.x, r.sun.y,
             r.sun.z, r.lit_patches, scene.size(), r.seconds);
    else
    info("sun ({:.6f}, {:.6f}, {:.6f}): {} of {} patches face it; pixel {:.4g} ({}x{} in {}x{} tiles of {}), bound {:.3g} "
         "(worst case; tolerance {:g}, {} patches above), {} clamped; {:.2f} s",
         r.sun.x, r.sun.y, r.sun.z, r.lit_patches, scene.size(), r.pixel_size, r.pixels_u, r.pixels_v, r.tiles_u, r.tiles_v,
         r.tile_size, r.error_bound, so.tolerance, r.under_resolved, r.clamped, r.seconds);
    // The bound is the worst case (an edge along the pixel rows); the turned grid makes the typical
    // error far smaller (sun_buffer.cpp), so a bound above the tolerance is reported, not warned of.
    report.set("patches", scene.size());
    report.set("objects", scene.objects.size());
    const double direction[3] = {r.sun.x, r.sun.y, r.sun.z};
    report.set_array("sun_direction", direction);
    report.set("method", o.method);
    report.set("renderer", r.renderer);
    if (o.method == "pixels") {
        report.set("pixel.size", r.pixel_size);
        report.set("pixel.wanted_size", r.wanted_pixel_size);
        report.set("pixel.tolerance", so.tolerance);
        report.set("pixel.max_pixels", so.max_pixels);
        report.set("pixel.grid_u", r.pixels_u);
        report.set("pixel.grid_v", r.pixels_v);
        report.set("tiles.size", r.tile_size);
        report.set("tiles.u", r.tiles_u);
        report.set("tiles.v", r.tiles_v);
    }
    report.set("patches_lit", r.lit_patches);
    report.set("clamps.count", r.clamped);
    report.set("clamps.max_overshoot", r.max_overshoot);
    if (o.method == "pixels") {
        report.set("error_bound.max", r.error_bound);
        report.set("error_bound.patches_above_tolerance", r.under_resolved);
    }
    report.set("sunlit_projected_area", r.sunlit_projected_area);
    report.set("time.sun", r.seconds);
    if (o.method == "pixels") {
        report.set("time.sun_parts.setup", r.seconds_setup);
        report.set("time.sun_parts.project", r.seconds_project);
        report.set("time.sun_parts.draw", r.seconds_draw);
        report.set("time.sun_parts.readback", r.seconds_readback);
        report.set("time.sun_parts.count", r.seconds_count);
    }
    watch.restart();
    if (!o.out.empty()) {
        if (o.by == "object")
            write_objects(o.out, scene, r);
        else
            write_patches(o.out, scene, r);
    }
    report.set("time.writing", watch.seconds());
    report.set("time.total", total.seconds());
    if (!o.report.empty()) report.write(o.report);
    return 0;
}

}  // namespace

void add_sun_command(CLI::App& app, std::function<int()>& action) {
    auto opts = std::make_shared<Options>();
    CLI::App* sub = app.add_subcommand("sun", "sunlit fraction of every patch or object for one sun direction (docs/urban.md)");
    add_scene_options(*sub, opts->scene);
    sub->add_option("--sun-direction", opts->direction, "X,Y,Z: the direction towards the sun (need not be unit)");
    sub->add_option("--sun", opts->angles,
                    "AZIMUTH,ELEVATION in degrees: azimuth clockwise from north (+y), east (+x) = 90; elevation above "
                    "the horizon (+z up), in [-90, 90]");
    sub->add_option("--sun-series", opts->series,
                    "SUN.csv: time,azimuth,elevation (or sun_x,sun_y,sun_z),direct_normal_irradiance,"
                    "diffuse_horizontal_irradiance; writes absorbed shortwave per step (docs/urban.md)");
    sub->add_option("--albedo", opts->albedo, "with --sun-series: A.csv object,albedo (every object, albedo in [0, 1))");
    sub->add_option("--matrix", opts->matrix, "with --sun-series: take F from F.ffm (made for this scene) instead of computing it");
    sub->add_option("--sky-patches", opts->sky_patches,
                    "with --sun-series: isotropic (default: sky view factor 1 - row sum of F) or tregenza (145 patches, traced)");
    sub->add_option("--sky-patches-out", opts->sky_out,
                    "with --sky-patches tregenza: write patch,object,p0..p144, the view factor of every patch to every sky patch");
    sub->add_option("-o,--out", opts->out,
                    "write patch,object,area,sunlit_fraction (--by object: object,area,sunlit_fraction); with --sun-series: "
                    "time,patch,object,area,albedo,direct,diffuse,reflected,absorbed (W/m^2)");
    sub->add_option("--by", opts->by, "patch (default) or object: area-weighted sunlit fraction per object")->default_val("patch");
    sub->add_option("--report", opts->report, "write a JSON report (pixel size, tiles, clamps, error bound, timings)");
    sub->add_option("--backend", opts->backend, "OpenGL context: auto, egl or osmesa")->default_val("auto");
    expert(sub->add_option("--tolerance", opts->sun.tolerance,
                           "relative error wanted on the smallest lit patch (bound perimeter x pixel / projected area)")
               ->default_val(1e-3));
    expert(sub->add_option("--max-pixels", opts->sun.max_pixels, "most pixels in all tiles together")
               ->default_val(std::uint64_t{1} << 27));
    expert(sub->add_option("--reflection-tolerance", opts->reflection_tolerance,
                           "--sun-series: stop the reflections when a sweep changes them by less than this x the incident power")
               ->default_val(1e-12));
    expert(sub->add_option("--batch", opts->batch, "--sun-series: steps computed, solved and written together (memory: 4 x steps x patches doubles)")
               ->default_val(32));
    expert(sub->add_option("--sun-method", opts->method,
                           "clip (default: shadow polygons clipped on the CPU, exact) or pixels (the GL item buffer, "
                           "--tolerance, --max-pixels, --tile)")
               ->default_val("clip"));
    expert(sub->add_option("--tile", opts->sun.tile, "tile side in pixels (0: min(4096, GL limits))")->default_val(0));
    sub->callback([opts, &action] {
        action = [opts] {
            if (opts->scene.quiet) set_log_level(LogLevel::Quiet);
            return run(*opts);
        };
    });
}

}  // namespace ffcube::cli
