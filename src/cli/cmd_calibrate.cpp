// ffcube calibrate: measures the cost model (pipeline/cost_model.hpp) on this machine and writes
// it for `--cost-model FILE`: the wall time of a hemicube pixel and of a piece on one worker of
// this machine's GL device, a ray's CPU time, and the CPU's time at the near-field correction's
// analytic work against the development machine's. Timing happens here only; runs that read the
// file are deterministic in it.
#include <fmt/format.h>

#include <algorithm>
#include <chrono>
#include <ctime>
#include <optional>
#include <span>
#include <vector>

#include "cli/commands.hpp"
#include "cli/common.hpp"
#include "ffcube/accuracy/near_field.hpp"
#include "ffcube/core/error.hpp"
#include "ffcube/core/log.hpp"
#include "ffcube/io/report.hpp"
#include "ffcube/pipeline/cost_model.hpp"
#include "ffcube/pipeline/row_source.hpp"
#include "ffcube/pipeline/scene_loading.hpp"
#include "ffcube/raycast/raycast_provider.hpp"

namespace ffcube::cli {
namespace {

// The CPU workload's time on the development machine (2-core VM, `ffcube calibrate`'s own
// workload below, the least of three runs on an idle machine, main at 95a625b: 0.988–0.998 s;
// docs/accuracy.md, "Cost model"). cpu_scale = this machine's time / this. The workload is the
// near-field analysis itself, so a change to that analysis changes it: measure again then (run
// `ffcube calibrate` on an idle development machine; it prints the workload's seconds).
constexpr double kReferenceWorkloadSeconds = 0.99;

struct Options {
    SceneFlags scene;
    int resolution = 256;
    std::string backend = "auto";
    std::uint32_t rows = 256;
    std::string output;
};

double thread_cpu_seconds() {
    timespec t{};
    clock_gettime(CLOCK_THREAD_CPUTIME_ID, &t);
    return static_cast<double>(t.tv_sec) + 1e-9 * static_cast<double>(t.tv_nsec);
}

// The analytic work `--far-field auto` and `--exact-visibility auto` budget: the near-field
// analysis of every row of the built-in Cornell box at its default mesh, with exact visibility
// past up to 8 occluders and no budget (shaft tests, Gauss rules, clipping, point evaluations).
// Thread CPU seconds, the least of `repeats` runs (others' load inflates, never deflates).
double cpu_workload_seconds(const Scene& scene, int repeats) {
    NearFieldOptions nf = near_field_options_for_hemicube(256);
    nf.far_field = NearFieldOptions::FarField::off;
    nf.exact_visibility_occluders = kAutoExactVisibilityOccluders;
    double best = 0;
    for (int r = 0; r < repeats; ++r) {
        const double t0 = thread_cpu_seconds();
        const NearFieldCorrector corrector(scene, nf);
        NearFieldScratch scratch;
        NearAnalysis analysis;
        for (std::uint32_t i = 0; i < static_cast<std::uint32_t>(scene.size()); ++i) corrector.plan_row(i, analysis, scratch);
        const double t = thread_cpu_seconds() - t0;
        best = r == 0 ? t : std::min(best, t);
    }
    return best;
}

// The scene piece_ns and ray_ns are timed on: a small generated city, kCityLots² lots of 3 × 3
// units, each a ground quad with a 2 × 2 building on it (four walls and a roof, 1 to 5 units
// tall), one patch a face (--no-subdivide): 864 pieces and patches, 1,728 triangles, the kind of
// mesh `--method auto` weighs rays against hemicubes on.
constexpr std::uint32_t kCityLots = 12;

Scene calibration_city(Report& report) {
    ObjModel m;
    m.source = "<calibration city>";
    m.objects = {"ground", "buildings"};
    m.materials.resize(1);
    const auto quad = [&](std::uint32_t object, std::initializer_list<Vec3> corners) {
        ObjFace f;
        f.object = object;
        for (const Vec3& c : corners) {
            f.v.push_back(static_cast<std::uint32_t>(m.positions.size()));
            m.positions.push_back(c);
        }
        f.line = static_cast<std::uint32_t>(m.faces.size() + 1);
        m.faces.push_back(std::move(f));
    };
    for (std::uint32_t k = 0; k < kCityLots * kCityLots; ++k) {
        const double x = 3.0 * (k % kCityLots), y = 3.0 * (k / kCityLots), h = 1.0 + (k * 7 % 5);
        const double x0 = x + 0.5, x1 = x + 2.5, y0 = y + 0.5, y1 = y + 2.5;
        quad(0, {{x, y, 0}, {x + 3, y, 0}, {x + 3, y + 3, 0}, {x, y + 3, 0}});
        quad(1, {{x0, y0, 0}, {x1, y0, 0}, {x1, y0, h}, {x0, y0, h}});  // front: -y
        quad(1, {{x1, y0, 0}, {x1, y1, 0}, {x1, y1, h}, {x1, y0, h}});  // +x
        quad(1, {{x1, y1, 0}, {x0, y1, 0}, {x0, y1, h}, {x1, y1, h}});  // +y
        quad(1, {{x0, y1, 0}, {x0, y0, 0}, {x0, y0, h}, {x0, y1, h}});  // -x
        quad(1, {{x0, y0, h}, {x1, y0, h}, {x1, y1, h}, {x0, y1, h}});  // roof
    }
    SceneOptions so;
    so.subdivide = false;
    return mesh_model(std::move(m), so, report, "calibration");
}

// Rows spread evenly over a scene of n rows.
std::vector<std::uint32_t> spread_rows(std::uint32_t count, std::uint32_t n) {
    std::vector<std::uint32_t> rows(count);
    for (std::uint32_t k = 0; k < count; ++k) rows[k] = static_cast<std::uint32_t>(std::uint64_t{k} * n / count);
    return rows;
}

// The fastest of four batches' wall seconds per row (warm-up first: shader compilation, first
// uploads); other jobs on the machine only ever add wall time.
double seconds_per_row(RowProvider& provider, const std::vector<std::uint32_t>& rows) {
    const auto count = static_cast<std::uint32_t>(rows.size());
    const std::vector<std::uint32_t> warm(rows.begin(), rows.begin() + std::min<std::uint32_t>(count, 4));
    provider.compute_rows(warm, [](std::uint32_t, const SparseRow&) {});
    constexpr std::uint32_t kBatches = 4;
    double per_row = 0;
    for (std::uint32_t b = 0; b < kBatches; ++b) {
        const std::span<const std::uint32_t> batch(rows.data() + std::uint64_t{b} * count / kBatches,
                                                   rows.data() + std::uint64_t{b + 1} * count / kBatches);
        if (batch.empty()) continue;
        const auto t0 = std::chrono::steady_clock::now();
        provider.compute_rows(batch, [](std::uint32_t, const SparseRow&) {});
        const double t = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count() /
                         static_cast<double>(batch.size());
        per_row = per_row == 0 ? t : std::min(per_row, t);
    }
    return per_row;
}

int run(const Options& o) {
    if (o.output.empty()) throw InputError("calibrate: -o FILE is required (the cost model to write)");
    check_output_path("--output", o.output);
    if (o.rows == 0) throw InputError("--rows 0: at least 1 row to time");
    RowOptions ro;
    ro.resolution = o.resolution;
    ro.backend = parse_backend(o.backend);
    ro.threads = 1;  // one worker: the cost of a row on one of them
    ro.correct = Correction::None;
    validate(ro);

    // The CPU workload's scene (the built-in box at its default mesh), and the scene to time
    // hemicubes on: the same unless the command line names another.
    Report report;
    const Scene builtin = load_and_mesh(SceneOptions{}, report);
    const SceneOptions& so = o.scene.scene;
    const bool default_scene = so.path.empty() && so.max_patch_edge == 0 && so.patches == 0 && so.materials.empty() &&
                               so.subdivide && so.contact_cuts == ContactCuts::Auto;
    std::optional<Scene> named;
    if (!default_scene) named = load_and_mesh(so, report);
    const Scene& scene = named ? *named : builtin;
    RowSource source = make_row_source(scene, ro);
    std::string device;
    if (const HemicubeRowProvider* h = source.hemicube()) device = fmt::format("{} ({})", h->backend(), h->renderer());
    const auto n = static_cast<std::uint32_t>(scene.size());
    const std::uint32_t count = std::min(o.rows, n);
    const double per_row = seconds_per_row(source.provider(), spread_rows(count, n));
    const double pixels = 3.0 * o.resolution * o.resolution;
    CostModel m;
    m.pixel_ns = per_row * 1e9 / pixels;
    info("hemicube on {}: {} rows at N = {} on one worker, the fastest of 4 batches {:.3f} ms a row: {:.3g} ns a "
         "pixel (built-in: {} ns)",
         device, count, o.resolution, 1e3 * per_row, m.pixel_ns, CostModel{}.pixel_ns);

    // piece_ns: hemicube rows of the calibration city at N = 32, where its pieces outweigh the
    // pixels (3 × 32² × pixel_ns taken off); ray_ns: its rows cast with a fixed count on this
    // thread, CPU seconds per ray. At most 64 rows each (a fraction of a second on llvmpipe).
    const Scene city = calibration_city(report);
    const auto city_rows = static_cast<std::uint32_t>(city.size());
    const std::vector<std::uint32_t> sample = spread_rows(std::min<std::uint32_t>({o.rows, city_rows, 64}), city_rows);
    {
        RowOptions co = ro;
        co.resolution = 32;
        RowSource city_source = make_row_source(city, co);
        const double city_row = seconds_per_row(city_source.provider(), sample);
        const double city_pixels_ns = 3.0 * 32 * 32 * m.pixel_ns;
        // A floor of 1e-3 ns (check_cost_model's least) where the pixels' share, measured at
        // another N, came out above the whole row.
        m.piece_ns = std::max(1e-3, (city_row * 1e9 - city_pixels_ns) / static_cast<double>(city.grids.size()));
        info("pieces: {} rows of a {}-piece city at N = 32, {:.3f} ms a row less {:.3f} ms of pixels: {:.3g} ns a piece "
             "(built-in: {} ns)",
             sample.size(), city.grids.size(), 1e3 * city_row, 1e-6 * city_pixels_ns, m.piece_ns, CostModel{}.piece_ns);
    }
    {
        RaycastOptions rc;
        rc.rays = 16384;
        rc.threads = 1;
        const RaycastRowProvider caster(city, rc);
        RaycastRowProvider::RowScratch scratch;
        SparseRow row;
        caster.cast_row(sample.front(), row, scratch);  // warm-up
        double best = 0;
        for (int r = 0; r < 3; ++r) {
            const double t0 = thread_cpu_seconds();
            for (const std::uint32_t i : sample) caster.cast_row(i, row, scratch);
            const double t = thread_cpu_seconds() - t0;
            best = r == 0 ? t : std::min(best, t);
        }
        m.ray_ns = std::max(1e-2, best * 1e9 / (static_cast<double>(sample.size()) * static_cast<double>(rc.rays)));
        info("rays: {} rows of the city at {} rays on one thread, the least of 3 runs: {:.3g} CPU ns a ray (built-in: {} ns)",
             sample.size(), rc.rays, m.ray_ns, CostModel{}.ray_ns);
    }
    const double cpu = cpu_workload_seconds(builtin, 3);
    m.cpu_scale = cpu / kReferenceWorkloadSeconds;
    info("CPU: the near-field workload in {:.3f} s against {:.3f} s on the development machine: cpu_scale {:.3g}", cpu,
         kReferenceWorkloadSeconds, m.cpu_scale);
    check_cost_model(m, "calibrate");
    write_cost_model(o.output, m, device, o.resolution, cpu, kReferenceWorkloadSeconds);
    info("wrote {}: use it with --cost-model {}", o.output, o.output);
    return 0;
}

}  // namespace

void add_calibrate_command(CLI::App& app, std::function<int()>& action) {
    auto opts = std::make_shared<Options>();
    CLI::App* sub = app.add_subcommand(
        "calibrate", "measure this machine's cost model (hemicube pixel, CPU) for --cost-model (docs/accuracy.md)");
    add_scene_options(*sub, opts->scene);
    sub->add_option("--resolution", opts->resolution, "hemicube top-face resolution to time (even, 8..8192)")
        ->default_val(256);
    sub->add_option("--backend", opts->backend, "OpenGL context: auto (EGL, then OSMesa), egl or osmesa")
        ->default_val("auto");
    sub->add_option("--rows", opts->rows, "rows to time, spread over the scene")->default_val(256);
    sub->add_option("-o,--output", opts->output, "the cost model to write (JSON)")->required();
    sub->callback([opts, &action] {
        action = [opts] {
            if (opts->scene.quiet) set_log_level(LogLevel::Quiet);
            return run(*opts);
        };
    });
}

}  // namespace ffcube::cli
