// The tolerance sweep on a scene of the user's (`ffcube bench --scene FILE`): rows made as
// `ffcube formfactors --tolerance E` makes them, on a sample of rows, against the ray caster with
// many rays (bench.hpp, run_scene_sweep).
#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <unordered_map>
#include <vector>

#include "ffcube/bench/bench.hpp"
#include "ffcube/core/error.hpp"
#include "ffcube/core/timer.hpp"
#include "ffcube/pipeline/row_source.hpp"
#include "ffcube/raycast/raycast_provider.hpp"

namespace ffcube {
namespace {

using Rows = std::unordered_map<std::uint32_t, SparseRow>;

Rows compute_sample(RowProvider& provider, const std::vector<std::uint32_t>& sample) {
    Rows out;
    provider.compute_rows(sample, [&](std::uint32_t i, const SparseRow& row) { out[i] = row; });
    return out;
}

// max(largest |entry error|, |sum error|) of `got` against `ref`.
double row_error(const SparseRow& got, const SparseRow& ref) {
    std::unordered_map<std::uint32_t, double> diff;
    for (std::size_t k = 0; k < ref.nnz(); ++k) diff[ref.col[k]] -= ref.val[k];
    for (std::size_t k = 0; k < got.nnz(); ++k) diff[got.col[k]] += got.val[k];
    double worst = 0.0;
    for (const auto& [j, d] : diff) worst = std::max(worst, std::abs(d));
    return std::max(worst, std::abs(got.sum() - ref.sum()));
}

}  // namespace

std::vector<std::uint32_t> sweep_sample(std::uint32_t n, std::size_t count) {
    std::vector<std::uint32_t> rows;
    if (n == 0 || count == 0) return rows;
    if (n <= count) {
        for (std::uint32_t i = 0; i < n; ++i) rows.push_back(i);
        return rows;
    }
    for (std::size_t k = 0; k < count; ++k)
        rows.push_back(static_cast<std::uint32_t>((2 * k + 1) * static_cast<std::uint64_t>(n) / (2 * count)));
    return rows;
}

std::vector<BenchResult> run_scene_sweep(const Scene& scene, const std::string& name, const SceneSweepOptions& options,
                                         const std::function<void(std::size_t, std::size_t, const BenchResult&)>& progress) {
    for (double e : options.tolerances)
        if (!(e >= kMinTolerance && e < 1.0))
            throw InputError(fmt::format("--tolerances {}: each target must be a number from {} to below 1", e, kMinTolerance));
    if (scene.size() == 0) throw InputError(fmt::format("--scene {}: the scene has no patches", name));
    const std::vector<std::uint32_t> sample = sweep_sample(static_cast<std::uint32_t>(scene.size()), options.sample_rows);

    // The reference: plain rays (no correction, no refinement), seeded apart from the runs.
    RaycastOptions ro;
    ro.rays = options.reference_rays;
    ro.threads = options.threads;
    ro.seed = options.seed ^ 0x9e3779b97f4a7c15ull;
    Rows ref;
    {
        RaycastRowProvider caster(scene, ro);
        ref = compute_sample(caster, sample);
    }

    std::vector<BenchResult> results;
    const double scale = static_cast<double>(scene.size()) / static_cast<double>(sample.size());
    for (double e : options.tolerances) {
        RowOptions o;
        o.method_auto = true;
        o.tolerance = e;
        o.tolerance_given = true;
        o.correct = Correction::Near;
        o.threads = options.threads;
        o.seed = options.seed;
        RowSource rows = make_row_source(scene, o);
        Stopwatch watch;
        const Rows got = compute_sample(rows.provider(), sample);
        const double seconds = watch.seconds();
        BenchResult r;
        r.case_name = name;
        r.group = "scene";
        r.method = "auto@tolerance";
        r.setting = fmt::format("E={:g}", e);
        r.value = e;
        r.patches = scene.size();
        r.seconds = seconds * scale;
        double sum = 0.0, estimate = 0.0;
        const std::span<const float> est = rows.ledger().tolerance_errors();  // each row's, noted as it came
        for (const std::uint32_t i : sample) {
            const double err = row_error(got.at(i), ref.at(i));
            r.errors.max_abs_error = std::max(r.errors.max_abs_error, err);
            sum += err;
            if (i < est.size() && std::isfinite(est[i])) estimate = std::max(estimate, static_cast<double>(est[i]));
        }
        r.errors.mean_abs_error = sum / static_cast<double>(sample.size());
        r.estimate = estimate;
        results.push_back(r);
        if (progress) progress(results.size(), options.tolerances.size(), results.back());
    }
    return results;
}

}  // namespace ffcube
