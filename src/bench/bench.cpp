// Running the benchmark, measuring errors and writing results.csv / results.json.
#include "ffcube/bench/bench.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <nlohmann/json.hpp>

#include "ffcube/core/error.hpp"
#include "ffcube/core/timer.hpp"
#include "ffcube/formfactor/checks.hpp"
#include "ffcube/hemicube/layout.hpp"
#include "ffcube/io/atomic_file.hpp"
#include "ffcube/pipeline/row_source.hpp"

namespace ffcube {

BenchErrors measure_errors(const CsrMatrix& F, const Scene& scene, const BenchCase& c) {
    const auto G = object_form_factors(F, scene);
    const std::size_t m = c.exact.size();
    // Case object k → scene object index (the mesher keeps objects by name).
    std::vector<std::size_t> idx(m);
    {
        std::vector<std::string> names;
        for (const NamedPolygon& p : c.polygons)
            if (std::find(names.begin(), names.end(), p.object) == names.end()) names.push_back(p.object);
        FFCUBE_CHECK(names.size() == m);
        for (std::size_t k = 0; k < m; ++k) {
            const auto it = std::find(scene.objects.begin(), scene.objects.end(), names[k]);
            FFCUBE_CHECK(it != scene.objects.end());
            idx[k] = static_cast<std::size_t>(it - scene.objects.begin());
        }
    }
    std::vector<double> area(scene.objects.size(), 0.0);
    for (const Patch& p : scene.patches) area[p.object] += p.area;

    BenchErrors e;
    std::size_t count = 0;
    double sum = 0;
    for (std::size_t a = 0; a < m; ++a) {
        bool row_known = true;
        double row_g = 0, row_exact = 0;
        for (std::size_t b = 0; b < m; ++b) {
            const double x = c.exact[a][b], g = G[idx[a]][idx[b]];
            row_g += g;
            if (std::isnan(x)) {
                row_known = false;
                continue;
            }
            row_exact += x;
            const double err = std::abs(g - x);
            e.max_abs_error = std::max(e.max_abs_error, err);
            sum += err;
            ++count;
            if (x > 0) e.max_rel_error = std::max(e.max_rel_error, err / x);
            const double ab = area[idx[a]] * g, ba = area[idx[b]] * G[idx[b]][idx[a]];
            if (std::max(ab, ba) > 0) e.reciprocity_dev = std::max(e.reciprocity_dev, std::abs(ab - ba) / std::max(ab, ba));
        }
        if (row_known) e.row_sum_dev = std::max(e.row_sum_dev, std::abs(row_g - row_exact));
    }
    e.mean_abs_error = count ? sum / static_cast<double>(count) : 0.0;
    return e;
}

std::vector<BenchResult> run_bench(const std::vector<BenchCase>& cases, const BenchOptions& options,
                                   const std::function<void(std::size_t, std::size_t, const BenchResult&)>& progress) {
    const auto& groups = bench_groups();
    if (options.suite != "all" && std::find(groups.begin(), groups.end(), options.suite) == groups.end())
        throw InputError(fmt::format("--suite {}: unknown suite (all, basic, enclosure, proximity, extreme, occlusion)",
                                     options.suite));
    for (int r : options.resolutions) check_row_resolution(r, "--resolutions");
    for (std::uint64_t r : options.rays)
        if (r == 0) throw InputError("--rays 0: each ray count must be at least 1");
    for (double e : options.tolerances)
        if (!(e >= kMinTolerance && e < 1.0))
            throw InputError(fmt::format("--tolerances {}: each target must be a number from {} to below 1", e, kMinTolerance));

    std::vector<const BenchCase*> selected;
    for (const BenchCase& c : cases)
        if (options.suite == "all" || c.group == options.suite) selected.push_back(&c);
    std::vector<Scene> scenes;
    for (const BenchCase* c : selected) scenes.push_back(build_bench_scene(*c));

    const std::size_t hemicube_runs = options.resolutions.size() * (options.corrected ? 2 : 1);
    const std::size_t per_case = hemicube_runs + options.rays.size() + options.tolerances.size();
    const std::size_t total = selected.size() * per_case;
    std::vector<BenchResult> results(total);
    std::size_t done = 0;
    auto record = [&](std::size_t k, std::size_t slot, const char* method, std::string setting, double value,
                      const CsrMatrix& F, double seconds) {
        BenchResult& r = results[k * per_case + slot];
        r.case_name = selected[k]->name;
        r.group = selected[k]->group;
        r.method = method;
        r.setting = std::move(setting);
        r.value = value;
        r.patches = scenes[k].size();
        r.seconds = seconds;
        r.errors = measure_errors(F, scenes[k], *selected[k]);
        if (progress) progress(++done, total, r);
    };
    // Every run gets its rows from the one factory the command line uses (pipeline/row_source.hpp),
    // so "hemicube+near" is exactly `ffcube formfactors --correct near` at the same settings.
    RowOptions base;
    base.threads = options.threads;
    base.backend = options.backend;
    base.seed = options.seed;
    base.near_k = options.near_k;
    // The rows, their time, and their largest row estimate (0 without the correction).
    struct Run {
        CsrMatrix F;
        double seconds = 0, estimate = 0;
    };
    auto run = [&](std::size_t k, const RowOptions& ro) {
        RowSource rows = make_row_source(scenes[k], ro);
        Stopwatch watch;
        Run out{compute_all_rows(rows.provider()), 0.0, 0.0};
        out.seconds = watch.seconds();
        for (const float e : rows.ledger().tolerance_errors())  // NaN (no correction) does not count
            if (e > out.estimate) out.estimate = e;
        return out;
    };
    // Hemicubes first (see the header: worker processes need a single-threaded process).
    for (std::size_t k = 0; k < selected.size(); ++k)
        for (std::size_t s = 0; s < options.resolutions.size(); ++s) {
            RowOptions ro = base;
            ro.method = RowMethod::Hemicube;
            ro.resolution = options.resolutions[s];
            ro.correct = Correction::None;
            const Run plain = run(k, ro);
            record(k, s, "hemicube", fmt::format("N={}", ro.resolution), ro.resolution, plain.F, plain.seconds);
            if (!options.corrected) continue;
            // The default `--correct near` as the command line runs it: a fresh source, so rows the
            // correction flags are measured by sub-hemicubes, and the time is the whole run's
            // (rendering, sub-hemicubes, correction).
            ro.correct = Correction::Near;
            const Run corrected = run(k, ro);
            record(k, options.resolutions.size() + s, "hemicube+near", fmt::format("N={}", ro.resolution), ro.resolution,
                   corrected.F, corrected.seconds);
        }
    for (std::size_t k = 0; k < selected.size(); ++k)
        for (std::size_t s = 0; s < options.rays.size(); ++s) {
            RowOptions ro = base;
            ro.method = RowMethod::Raycast;
            ro.rays = options.rays[s];
            ro.correct = Correction::None;
            const Run cast = run(k, ro);
            record(k, hemicube_runs + s, "raycast", fmt::format("rays={}", ro.rays), static_cast<double>(ro.rays), cast.F,
                   cast.seconds);
        }
    // Accuracy by target: the rows refined to E as the command line makes them (the default
    // correction on), each run's promise (its largest row estimate) beside its true errors.
    for (std::size_t k = 0; k < selected.size(); ++k)
        for (std::size_t s = 0; s < options.tolerances.size(); ++s) {
            RowOptions ro = base;
            ro.method = RowMethod::Raycast;
            ro.tolerance = options.tolerances[s];
            ro.correct = Correction::Near;
            const Run refined = run(k, ro);
            const std::size_t slot = hemicube_runs + options.rays.size() + s;
            results[k * per_case + slot].estimate = refined.estimate;
            record(k, slot, "raycast@tolerance", fmt::format("E={:g}", ro.tolerance), ro.tolerance, refined.F,
                   refined.seconds);
        }
    return results;
}

void write_bench_csv(const std::filesystem::path& path, const std::vector<BenchResult>& results) {
    write_file_atomically(path, [&](std::ostream& os) {
        os << "case,group,method,setting,seconds,max_abs_error,mean_abs_error,max_rel_error,row_sum_dev,"
              "reciprocity_dev,patches,estimate\n";
        for (const BenchResult& r : results)
            os << fmt::format("{},{},{},{},{:.6g},{:.6g},{:.6g},{:.6g},{:.6g},{:.6g},{},{}\n", r.case_name, r.group,
                              r.method, r.setting, r.seconds, r.errors.max_abs_error, r.errors.mean_abs_error,
                              r.errors.max_rel_error, r.errors.row_sum_dev, r.errors.reciprocity_dev, r.patches,
                              std::isnan(r.estimate) ? std::string() : fmt::format("{:.6g}", r.estimate));
    });
}

void write_bench_json(const std::filesystem::path& path, const std::vector<BenchResult>& results,
                      const BenchOptions& options) {
    nlohmann::ordered_json j;
    j["suite"] = options.suite;
    j["quick"] = options.quick;
    j["resolutions"] = options.resolutions;
    j["rays"] = options.rays;
    j["tolerances"] = options.tolerances;
    j["threads"] = options.threads;
    j["seed"] = options.seed;
    j["results"] = nlohmann::ordered_json::array();
    for (const BenchResult& r : results) {
        nlohmann::ordered_json o;
        o["case"] = r.case_name;
        o["group"] = r.group;
        o["method"] = r.method;
        o["setting"] = r.setting;
        o["value"] = r.value;
        o["patches"] = r.patches;
        o["seconds"] = r.seconds;
        o["max_abs_error"] = r.errors.max_abs_error;
        o["mean_abs_error"] = r.errors.mean_abs_error;
        o["max_rel_error"] = r.errors.max_rel_error;
        o["row_sum_dev"] = r.errors.row_sum_dev;
        o["reciprocity_dev"] = r.errors.reciprocity_dev;
        if (!std::isnan(r.estimate)) o["estimate"] = r.estimate;
        j["results"].push_back(std::move(o));
    }
    const std::string text = j.dump(2) + "\n";
    write_file_atomically(path, [&](std::ostream& os) { os << text; });
}

}  // namespace ffcube
