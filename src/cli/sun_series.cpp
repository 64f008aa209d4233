// ffcube sun --sun-series (cli/sun_series.hpp). Per step s and patch i:
//   direct_i  = DNI_s × sunlit_fraction_i × cos θ_i       (shadow polygons, or the item buffer along
//                                                          the sun; 0 when the sun is at or below
//                                                          the horizon)
//   diffuse_i = DHI_s × SVF_i                              (isotropic sky: SVF_i = 1 − Σ_j F_ij, or
//                                                          Σ_p V_ip over the Tregenza patches)
//   reflected_i from B = E + ρ F B (solver/shortwave.hpp), all daylight steps of a batch at once;
//   absorbed_i = (1 − ρ_i)(direct_i + diffuse_i + reflected_i).
#include "cli/sun_series.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <memory>
#include <optional>
#include <span>

#include "ffcube/core/error.hpp"
#include "ffcube/core/input_file.hpp"
#include "ffcube/core/log.hpp"
#include "ffcube/core/timer.hpp"
#include "ffcube/formfactor/sky.hpp"
#include "ffcube/io/atomic_file.hpp"
#include "ffcube/io/csv.hpp"
#include "ffcube/io/ffm.hpp"
#include "ffcube/io/report.hpp"
#include "ffcube/pipeline/form_factors.hpp"
#include "ffcube/pipeline/row_source.hpp"
#include "ffcube/pipeline/scene_loading.hpp"
#include "ffcube/raycast/sky_patches.hpp"
#include "ffcube/solver/shortwave.hpp"

namespace ffcube::cli {
namespace {

std::string num(double v) { return fmt::format("{:.12g}", v); }

// Irradiances per step of a batch and patch (W/m²): [s][i].
struct Series {
    std::vector<std::vector<double>> direct, diffuse, reflected, absorbed;
};

// The lines of a batch of steps (r holds the batch's irradiances, in step order).
void write_lines(std::ostream& os, const Scene& scene, std::span<const SunStep> steps, const std::vector<double>& albedo,
                 const Series& r, bool by_object) {
    if (!by_object) {
        // One buffer per step, formatted with fmt (the bytes of num(), without a string per number).
        std::vector<std::string> object(scene.objects.size());
        for (std::size_t k = 0; k < object.size(); ++k) object[k] = csv_field(scene.objects[k]);
        fmt::memory_buffer buf;
        for (std::size_t s = 0; s < steps.size(); ++s) {
            const std::string time = csv_field(steps[s].time);
            buf.clear();
            for (std::size_t i = 0; i < scene.size(); ++i) {
                const Patch& p = scene.patches[i];
                fmt::format_to(std::back_inserter(buf), "{},{},{},{:.12g},{:.12g},{:.12g},{:.12g},{:.12g},{:.12g}\n", time, i,
                               object[p.object], p.area, albedo[i], r.direct[s][i], r.diffuse[s][i], r.reflected[s][i],
                               r.absorbed[s][i]);
            }
            os.write(buf.data(), static_cast<std::streamsize>(buf.size()));
        }
        return;
    }
    // Per object: area-weighted means Σ A x / Σ A of its patches.
    const std::size_t m = scene.objects.size();
    std::vector<double> area(m, 0.0);
    for (const Patch& p : scene.patches) area[p.object] += p.area;
    for (std::size_t s = 0; s < steps.size(); ++s) {
        std::vector<std::array<double, 4>> sum(m, {0.0, 0.0, 0.0, 0.0});
        for (std::size_t i = 0; i < scene.size(); ++i) {
            const Patch& p = scene.patches[i];
            sum[p.object][0] += p.area * r.direct[s][i];
            sum[p.object][1] += p.area * r.diffuse[s][i];
            sum[p.object][2] += p.area * r.reflected[s][i];
            sum[p.object][3] += p.area * r.absorbed[s][i];
        }
        const std::string time = csv_field(steps[s].time);
        for (std::size_t k = 0; k < m; ++k) {
            os << time << ',' << csv_field(scene.objects[k]) << ',' << num(area[k]);
            for (const double x : sum[k]) os << ',' << num(area[k] > 0.0 ? x / area[k] : 0.0);
            os << '\n';
        }
    }
}

// patch,object,p0,...,p144: V_ip per patch of the scene and Tregenza patch (docs/urban.md).
void write_sky_patches(const std::string& path, const Scene& scene, const SkyPatchViewFactors& v) {
    write_file_atomically(path, [&](std::ostream& os) {
        os << "patch,object";
        for (std::uint32_t p = 0; p < v.sky; ++p) os << ",p" << p;
        os << '\n';
        for (std::size_t i = 0; i < scene.size(); ++i) {
            os << i << ',' << csv_field(scene.objects[scene.patches[i].object]);
            for (std::uint32_t p = 0; p < v.sky; ++p) os << ',' << num(v.v[i * v.sky + p]);
            os << '\n';
        }
    });
}

}  // namespace

int run_sun_series(const SunSeriesRequest& q) {
    Stopwatch total;
    check_output_path("-o", q.out);
    check_output_path("--report", q.report);
    check_output_path("--sky-patches-out", q.sky_out);
    if (!q.sky_out.empty() && q.sky_patches != "tregenza")
        throw InputError("--sky-patches-out writes the Tregenza view factors: give --sky-patches tregenza");
    if (q.by != "patch" && q.by != "object") throw InputError(fmt::format("--by {}: must be patch or object", q.by));
    if (q.sky_patches != "isotropic" && q.sky_patches != "tregenza")
        throw InputError(fmt::format("--sky-patches {}: must be isotropic (the sky view factor 1 - row sum of F) or tregenza "
                                     "(145 patches, traced)",
                                     q.sky_patches));
    if (q.albedo.empty()) throw InputError("--sun-series needs --albedo A.csv (object,albedo)");
    if (!(q.tolerance > 0.0 && q.tolerance < 1e-3))
        throw InputError(fmt::format("--reflection-tolerance {}: must be in (0, 1e-3)", q.tolerance));
    if (q.batch < 1) throw InputError("--batch 0: must be at least 1");
    const std::vector<SunStep> steps = parse_sun_series(read_input_file(q.series, "a CSV file", "the sun series"), q.series);
    const std::string albedo_text = read_input_file(q.albedo, "a CSV file", "the albedos");

    Report report;
    report.set("command", "sun");
    report.set("mode", "series");
    Stopwatch watch;
    const Scene scene = load_and_mesh(q.scene.scene, report);
    report.set("time.loading", watch.seconds());
    const std::vector<double> object_albedo = parse_albedo_csv(albedo_text, q.albedo, scene.objects);
    const std::size_t n = scene.size();
    std::vector<double> albedo(n);
    for (std::size_t i = 0; i < n; ++i) albedo[i] = object_albedo[scene.patches[i].object];
    report.set("patches", n);
    report.set("objects", scene.objects.size());
    report.set("steps", steps.size());

    // F: once, from the file (checked against the scene) or computed.
    watch.restart();
    CsrMatrix F;
    if (!q.matrix.empty()) {
        FfmFile ffm = read_ffm(q.matrix);
        check_ffm_matches(ffm, scene);
        F = std::move(ffm.matrix);
        report.set("rows", "matrix");
        report.set("matrix", q.matrix);
    } else {
        RowOptions ro;
        ro.method_auto = true;
        ro.backend = q.sun.backend;
        validate(ro);
        RowSource rows = make_row_source(scene, resolve_row_method(ro, scene.drawn_scene()));
        for (const std::string& line : describe(rows)) info("{}", line);
        report.set("rows", rows.provider().name());
        FormFactorOptions fo;  // the one path (pipeline/form_factors.hpp); no reciprocity check to report
        fo.reciprocity = false;
        F = form_factor_matrix(scene, rows, report, fo);
    }
    report.set("time.rows", watch.seconds());
    const auto patch_name = [&scene](std::uint32_t i) {
        return fmt::format("patch {} of object '{}'", i, scene.objects[scene.patches[i].object]);
    };
    const ShortwaveSystem system = make_shortwave_system(F, albedo, patch_name);
    report.set("reflections.contraction", system.contraction);

    // The sky: what an unobstructed horizontal plane's DHI becomes on each patch, per W/m² of DHI.
    watch.restart();
    std::vector<double> svf;
    SkyPatchViewFactors v;  // --sky-patches tregenza: written with the other outputs, at the end
    if (q.sky_patches == "isotropic") {
        svf = sky_view_factors(F);
    } else {
        v = sky_patch_view_factors(scene, tregenza_patches());
        svf.assign(n, 0.0);
        for (std::size_t i = 0; i < n; ++i)
            for (std::uint32_t p = 0; p < v.sky; ++p) svf[i] += v.v[i * v.sky + p];  // isotropic radiance DHI/π per patch
        report.set("sky.rays", v.rays);
        info("sky: {} Tregenza patches, {} rays, {:.2f} s", v.sky, v.rays, v.seconds);
    }
    report.set("sky.model", q.sky_patches);
    report.set("time.sky", watch.seconds());

    // Batch by batch of steps (memory: a batch's irradiances, not the whole series): the direct
    // beam of each step (one item buffer with the sun up), the sky, the reflections of the steps
    // with light all at once, then the batch's lines.
    std::optional<AtomicFile> file;
    if (!q.out.empty()) {
        file.emplace(q.out);
        file->stream() << (q.by == "object" ? "time,object,area,direct,diffuse,reflected,absorbed\n"
                                            : "time,patch,object,area,albedo,direct,diffuse,reflected,absorbed\n");
    }
    ShortwaveControl control;
    control.tolerance = q.tolerance;
    std::vector<double> incident_w(steps.size(), 0.0), absorbed_w(steps.size(), 0.0), escaped_w(steps.size(), 0.0);
    std::uint32_t max_sweeps = 0;
    std::size_t renders = 0, solved = 0;
    double sun_seconds = 0.0, solve_seconds = 0.0, write_seconds = 0.0;
    std::array<double, 5> sun_parts{};  // SunResult::seconds_setup ... seconds_count, summed
    std::unique_ptr<GlContext> context;  // one for every step's item buffer, made at the first
    for (std::size_t b0 = 0; b0 < steps.size(); b0 += q.batch) {
        const std::size_t b1 = std::min(steps.size(), b0 + q.batch);
        Series r;
        r.direct.assign(b1 - b0, std::vector<double>(n, 0.0));
        r.diffuse.assign(b1 - b0, std::vector<double>(n, 0.0));
        r.reflected.assign(b1 - b0, std::vector<double>(n, 0.0));
        r.absorbed.assign(b1 - b0, std::vector<double>(n, 0.0));
        std::vector<std::size_t> lit;  // steps of the batch (0-based in it) with incident energy
        for (std::size_t s = b0; s < b1; ++s) {
            const SunStep& st = steps[s];
            const bool sun_up = st.z > 0.0 && st.dni > 0.0;
            if (sun_up) {
                if (!context && q.method == "pixels") context = create_headless_context(q.sun.backend);
                const SunResult sun = q.method == "pixels" ? sunlit_fractions(scene, Vec3(st.x, st.y, st.z), q.sun, *context)
                                                           : sunlit_fractions_clipped(scene, Vec3(st.x, st.y, st.z));
                sun_seconds += sun.seconds;
                sun_parts[0] += sun.seconds_setup, sun_parts[1] += sun.seconds_project, sun_parts[2] += sun.seconds_draw;
                sun_parts[3] += sun.seconds_readback, sun_parts[4] += sun.seconds_count;
                ++renders;
                for (std::size_t i = 0; i < n; ++i)
                    r.direct[s - b0][i] = st.dni * sun.fraction[i] * std::max(0.0, sun.cosine[i]);
            }
            for (std::size_t i = 0; i < n; ++i) r.diffuse[s - b0][i] = st.dhi * svf[i];
            if (sun_up || st.dhi > 0.0) lit.push_back(s - b0);
        }
        watch.restart();
        if (!lit.empty()) {
            const auto k = static_cast<std::uint32_t>(lit.size());
            std::vector<double> Q(n * k);
            for (std::size_t i = 0; i < n; ++i)
                for (std::uint32_t c = 0; c < k; ++c)
                    Q[i * k + c] = scene.patches[i].area * (r.direct[lit[c]][i] + r.diffuse[lit[c]][i]);
            const ShortwaveSolution x = solve_shortwave(system, Q, k, control);
            max_sweeps = std::max(max_sweeps, x.iterations);
            solved += k;
            for (std::uint32_t c = 0; c < k; ++c) {
                const std::size_t s = lit[c];
                for (std::size_t i = 0; i < n; ++i) {
                    const double a = scene.patches[i].area;
                    incident_w[b0 + s] += Q[i * k + c];
                    absorbed_w[b0 + s] += x.absorbed[i * k + c];
                    r.reflected[s][i] = a > 0.0 ? x.reflected[i * k + c] / a : 0.0;
                    r.absorbed[s][i] = a > 0.0 ? x.absorbed[i * k + c] / a : 0.0;
                }
                escaped_w[b0 + s] = x.escaped[c];
            }
        }
        solve_seconds += watch.seconds();
        watch.restart();
        if (file) write_lines(file->stream(), scene, std::span(steps).subspan(b0, b1 - b0), albedo, r, q.by == "object");
        write_seconds += watch.seconds();
    }
    double worst = 0.0;
    for (std::size_t s = 0; s < steps.size(); ++s)
        if (incident_w[s] > 0.0) worst = std::max(worst, std::abs(absorbed_w[s] + escaped_w[s] - incident_w[s]) / incident_w[s]);
    report.set("time.sun", sun_seconds);
    report.set("sun.renders", renders);
    report.set("sun.method", q.method);
    if (q.method == "pixels") {
        report.set("time.sun_parts.setup", sun_parts[0]);
        report.set("time.sun_parts.project", sun_parts[1]);
        report.set("time.sun_parts.draw", sun_parts[2]);
        report.set("time.sun_parts.readback", sun_parts[3]);
        report.set("time.sun_parts.count", sun_parts[4]);
    }
    info("direct beam: {} item buffers, {:.2f} s", renders, sun_seconds);
    const double rate = solve_seconds > 0.0 ? static_cast<double>(solved) / solve_seconds : 0.0;
    report.set("time.reflections", solve_seconds);
    report.set("reflections.steps_solved", solved);
    report.set("reflections.steps_per_second", rate);
    report.set("reflections.max_sweeps", max_sweeps);
    report.set("reflections.tolerance", q.tolerance);
    report.set_array("energy.incident", incident_w);
    report.set_array("energy.absorbed", absorbed_w);
    report.set_array("energy.escaped", escaped_w);
    report.set("energy.max_relative_error", worst);
    info("reflections: {} steps in {:.3f} s ({:.0f} steps/s), at most {} passes over F (contraction {:.3g}); balance error {:.3g}",
         solved, solve_seconds, rate, max_sweeps, system.contraction, worst);
    watch.restart();
    if (file) file->commit();
    if (!q.sky_out.empty()) write_sky_patches(q.sky_out, scene, v);
    report.set("time.writing", write_seconds + watch.seconds());
    report.set("time.total", total.seconds());
    if (!q.report.empty()) report.write(q.report);
    return 0;
}

}  // namespace ffcube::cli
