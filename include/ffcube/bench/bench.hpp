// The benchmark against analytic form factors (`ffcube bench`): scenes built in code whose
// object-to-object form factors are known exactly, run through the hemicube at several
// resolutions and the ray caster at several ray counts, each timed and measured.
//
// Exact values come from geometry/analytic.hpp: closed forms where one exists (Howell C-11,
// C-14), the polygon-to-polygon contour integral otherwise, and symmetry for the occluded cases
// (see each case's description). Meshing: each case fixes its own max patch edge (documented
// per case in docs/benchmarks.md: about 64–256 patches per object by default, fewer with quick).
#pragma once

#include <cstdint>
#include <filesystem>
#include <functional>
#include <limits>
#include <string>
#include <vector>

#include "ffcube/scene/polygons.hpp"
#include "ffcube/formfactor/sparse.hpp"
#include "ffcube/gl/context.hpp"
#include "ffcube/scene/scene.hpp"

namespace ffcube {

struct BenchCase {
    std::string name;   // unique, e.g. "parallel_d1"
    std::string group;  // basic, enclosure, proximity, extreme, occlusion
    std::string description;
    std::vector<NamedPolygon> polygons;
    double max_patch_edge = 0;  // meshing (scene units)
    // exact[a][b]: object-to-object F in the order objects are first named in `polygons`;
    // NaN where no exact value is known (such entries are not measured).
    std::vector<std::vector<double>> exact;
};

// The suite: every case of every group. quick: fewer cases (one or two per group) meshed more
// coarsely. Exact values are computed here (milliseconds).
std::vector<BenchCase> bench_cases(bool quick);
// Group names in plot order.
const std::vector<std::string>& bench_groups();

// The meshed scene of a case (through the real mesher).
Scene build_bench_scene(const BenchCase& c);

// Errors of a computed matrix F against a case's exact values, at object level
// (G = object_form_factors(F, scene)), over the entries with a known exact value:
struct BenchErrors {
    double max_abs_error = 0;   // max |G_ab − exact_ab|
    double mean_abs_error = 0;  // mean |G_ab − exact_ab|
    double max_rel_error = 0;   // max |G_ab − exact_ab| / exact_ab over exact_ab > 0
    double row_sum_dev = 0;     // max over objects with a wholly known row: |Σ_b G_ab − Σ_b exact_ab|
    double reciprocity_dev = 0; // max over object pairs: |A_a G_ab − A_b G_ba| / max(A_a G_ab, A_b G_ba)
};
BenchErrors measure_errors(const CsrMatrix& F, const Scene& scene, const BenchCase& c);

struct BenchOptions {
    std::string suite = "all";            // "all" or one group name
    std::vector<int> resolutions;         // hemicube settings (even, 8..8192); none: no hemicube runs
    std::vector<std::uint64_t> rays;      // raycast settings (rays per row ≥ 1); none: no raycast runs
    // Accuracy targets (--tolerance E, in [1e-9, 1)): one run each of the ray caster refined to E
    // with the near-field correction, as `ffcube formfactors --method raycast --tolerance E`
    // makes its rows (method "raycast@tolerance"); none: no such runs.
    std::vector<double> tolerances;
    bool quick = false;
    unsigned threads = 0;                 // 0: every core (both methods)
    Backend backend = Backend::Auto;
    std::uint64_t seed = 0x5eed;
    // Also measure each hemicube setting with the default near-field correction
    // (accuracy/near_field.hpp) as method "hemicube+near": a run of its own, timed whole, with
    // sub-hemicubes where the correction asks for them (what `--correct near` costs).
    bool corrected = true;
    double near_k = 3.0;
};

// One line of results.csv.
struct BenchResult {
    // method "hemicube" (setting "N=256"), "hemicube+near", "raycast" (setting "rays=1000") or
    // "raycast@tolerance" (setting "E=0.001")
    std::string case_name, group, method, setting;
    double value = 0;                                // the resolution or ray count, for plotting
    std::size_t patches = 0;
    double seconds = 0;  // wall seconds of the row computation (provider start-up excluded)
    // raycast@tolerance: the largest of the rows' own error estimates (the run's promise, to set
    // beside its true errors); NaN for the other methods.
    double estimate = std::numeric_limits<double>::quiet_NaN();
    BenchErrors errors;
};

// Runs every selected case with every setting. All hemicube runs come first: the hemicube's
// worker processes are forked only while this process runs a single thread, and Embree leaves
// its thread pool alive. progress(done, total, line) is called after each run.
// Throws InputError for an unknown suite or a bad setting, before running anything.
std::vector<BenchResult> run_bench(const std::vector<BenchCase>& cases, const BenchOptions& options,
                                   const std::function<void(std::size_t, std::size_t, const BenchResult&)>& progress = {});

// A scene of the user's (`ffcube bench --scene FILE`), which has no exact values: each target E
// of the sweep is run as `ffcube formfactors --tolerance E` makes its rows (--method auto, the
// default correction) on a sample of rows, and each sampled row is compared with the ray
// caster's at reference_rays rays (plain rows, another seed). A row's error is the larger of its
// largest |entry error| and its |sum error| (what its estimate bounds); a result's
// max_abs_error and mean_abs_error are their max and mean over the sample (no object factors),
// its estimate the sample's largest row estimate, and its seconds the sample's wall time scaled
// to every row (n / sample). The sample: sample_rows rows evenly spaced over the scene's rows.
struct SceneSweepOptions {
    std::vector<double> tolerances;     // each in [kMinTolerance, 1)
    std::size_t sample_rows = 64;       // rows compared (all of them if the scene has fewer)
    // The reference's rays per row (Owen-scrambled Sobol' rays, as every ray-cast row): on a
    // city their error falls about as R^-0.63 (docs/accuracy.md), so 2^22 is about 3 times more
    // accurate than rows refined to 1e-4 at their budget of 64/E = 640,000 rays, the issue's
    // requirement for a reference; below 1e-4 it is not (say so beside such results).
    std::uint64_t reference_rays = std::uint64_t{1} << 22;
    unsigned threads = 0;
    std::uint64_t seed = 0x5eed;
};
// Rows of `scene` compared as above; case_name `name`, group "scene", method "auto@tolerance".
// Throws InputError for a bad target or an empty scene.
std::vector<BenchResult> run_scene_sweep(const Scene& scene, const std::string& name, const SceneSweepOptions& options,
                                         const std::function<void(std::size_t, std::size_t, const BenchResult&)>& progress = {});
// The rows a sweep samples: `count` rows evenly spaced over 0..n−1 (all of them when n ≤ count).
std::vector<std::uint32_t> sweep_sample(std::uint32_t n, std::size_t count);

// Outputs, each written atomically.
void write_bench_csv(const std::filesystem::path& path, const std::vector<BenchResult>& results);
void write_bench_json(const std::filesystem::path& path, const std::vector<BenchResult>& results,
                      const BenchOptions& options);
// The log–log plot of error (y: max over the group's cases of max_abs_error) against time
// (x: seconds summed over the group's cases), one curve per (method, group), points ordered by
// setting. The SVG is hand-written; the PNG is the same plot drawn by a small rasteriser.
std::string bench_plot_svg(const std::vector<BenchResult>& results);
void write_bench_plot_svg(const std::filesystem::path& path, const std::vector<BenchResult>& results);
void write_bench_plot_png(const std::filesystem::path& path, const std::vector<BenchResult>& results);

}  // namespace ffcube
