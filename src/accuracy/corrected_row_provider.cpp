// CorrectedRowProvider: wraps a RowProvider; each row is planned (sub-hemicubes, skip) from its
// analysis before the inner provider measures it, and corrected after, both as stages the inner
// provider runs on its worker threads (RowProvider::RowStages). Owns the scratch space the
// corrector works in, so that rows allocate nothing in the steady state.
#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <memory>
#include <mutex>
#include <string>

#include "accuracy/exposed_points.hpp"
#include "accuracy/rebalance.hpp"
#include "accuracy/row_range.hpp"
#include "accuracy/scratch.hpp"
#include "ffcube/accuracy/near_field.hpp"
#include "ffcube/core/error.hpp"
#include "ffcube/core/log.hpp"
#include "ffcube/core/stats.hpp"
#include "ffcube/core/timer.hpp"
#include "ffcube/geometry/quadrature.hpp"

namespace ffcube {

// Scratch spaces and analysis buffers, taken and given back under a lock by the plan and finish
// stages (several at once, on the inner provider's threads). There are as many as were ever in
// use at once: the inner provider's threads, and its window of rows in flight.
struct CorrectedRowProvider::Pools {
    using Entries = std::vector<std::pair<std::uint32_t, double>>;
    std::mutex mutex;
    std::vector<std::unique_ptr<NearFieldScratch>> scratch;
    std::vector<Entries> entries;

    // A scratch space, and a spare buffer moved into `exact` (when one is free).
    std::unique_ptr<NearFieldScratch> take(Entries& exact) {
        std::unique_ptr<NearFieldScratch> s;
        {
            const std::lock_guard lock(mutex);
            if (!scratch.empty()) {
                s = std::move(scratch.back());
                scratch.pop_back();
            }
            if (!entries.empty()) {
                exact = std::move(entries.back());
                entries.pop_back();
            }
        }
        return s ? std::move(s) : std::make_unique<NearFieldScratch>();
    }
    // A scratch space alone (for a correction: its analysis is the row's own).
    std::unique_ptr<NearFieldScratch> take() {
        {
            const std::lock_guard lock(mutex);
            if (!scratch.empty()) {
                std::unique_ptr<NearFieldScratch> s = std::move(scratch.back());
                scratch.pop_back();
                return s;
            }
        }
        return std::make_unique<NearFieldScratch>();
    }
    // Rows handed on as measured by the range check (for the warning after the call).
    std::vector<std::uint32_t> out_of_range;
    void note_out_of_range(std::uint32_t i) {
        const std::lock_guard lock(mutex);
        out_of_range.push_back(i);
    }
    // Adds one row's statistics (a fresh NearFieldStats filled by correct()) to the call's: sums,
    // and the least and largest, so the totals do not depend on the order rows finish in (but for
    // the seconds, which are timings).
    void add(NearFieldStats& total, const NearFieldStats& row) {
        const std::lock_guard lock(mutex);
        stats::merge(total, row);
    }
    void give_back(std::unique_ptr<NearFieldScratch> s) {
        const std::lock_guard lock(mutex);
        scratch.push_back(std::move(s));
    }
    // Keeps exact's buffer for a later analysis (when it has one: an analysis made by correct()
    // itself lives in its scratch space, and the slot's is empty).
    void recycle(Entries& exact) {
        if (exact.capacity() == 0) return;
        exact.clear();
        const std::lock_guard lock(mutex);
        entries.push_back(std::move(exact));
        exact = Entries{};
    }
};

CorrectedRowProvider::CorrectedRowProvider(const Scene& scene, RowProvider& inner, const NearFieldOptions& options)
    : inner_(inner),
      scene_(scene),
      corrector_(scene, options),
      options_(options),
      pools_(std::make_unique<Pools>()) {
    if (inner.size() != scene.size())
        throw InputError(fmt::format("near-field correction: the provider has {} rows, the scene {} patches", inner.size(),
                                     scene.size()));
}

CorrectedRowProvider::~CorrectedRowProvider() = default;

// The sender rule of a row measured by sub-hemicubes: for a sender that a facet cuts and partly
// encloses, points on its exposed part (exposed_points.hpp; the cell grid and its ray scene
// are made at the first such question, once, and shared by the threads); for every other sender
// the patch's quadrature points, 2 × 2 (sampled) or 4 × 4 (sampled_fine: an occluder touches it).
void CorrectedRowProvider::sender_points(std::uint32_t i, RowRequest& request) {
    std::call_once(exposed_once_, [&] { exposed_ = std::make_unique<ExposedPoints>(scene_); });
    if (exposed_->rule(i, request.points, request.weights)) {
        request.partly_enclosed = true;
        return;
    }
    const auto v = scene_.patch_vertices(i);
    patch_quadrature(std::span<const Vec3>(v.data(), scene_.patches[i].count),
                     request.plan == RowPlan::sampled_fine ? 4 : 2, request.points, request.weights);
}


void CorrectedRowProvider::compute_rows(std::span<const std::uint32_t> rows, const RowSink& sink) {
    // Near analysis per listed row (slot k for rows[k]), made when its row is planned or, without
    // plans, when the row is corrected; slot k is touched only by row k's plan and finish, which
    // run one after the other on one thread.
    analyses_.assign(rows.size(), NearAnalysis{});
    // Each row's figures go with it (SparseRow::side); a row listed twice is measured twice.
    for (const std::uint32_t i : rows)
        if (i >= inner_.size())
            throw InternalError(fmt::format("CorrectedRowProvider::compute_rows: row {} is out of range ({} rows)", i,
                                            inner_.size()));
    // Rows with a near pair that may be occluded are measured by sub-hemicubes at the sender's
    // quadrature points (the pair keeps a value with its own visibility and sender quadrature);
    // rows whose every pair is known are not measured. Each row's plan comes from its analysis,
    // a function of the scene and the row only, and so is its correction: the inner provider
    // runs both on its worker threads (RowProvider::RowStages), where they overlap the other
    // workers' measuring, and the rows do not depend on the thread count.
    const bool sample = options_.sub_hemicubes && inner_.can_sample_sender();
    const std::uint64_t cast_fine_rays = inner_.cast_fine_row_rays();
    RowStages stages;
    if (sample) {
        stages.plan = [&](std::size_t k, std::uint32_t i, RowRequest& request) {
            NearAnalysis& a = analyses_[k];
            std::unique_ptr<NearFieldScratch> scratch = pools_->take(a.exact);
            request.plan = corrector_.plan_row(i, a, *scratch);
            pools_->give_back(std::move(scratch));
            // The sender points of a sampled row, unless it goes to the ray caster (which
            // samples the whole sender itself).
            const bool cast = request.plan == RowPlan::sampled_fine && cast_fine_rays > 0;
            if ((request.plan == RowPlan::sampled || request.plan == RowPlan::sampled_fine) && !cast)
                sender_points(i, request);
        };
    }
    // A provider that refines rows to a tolerance (the ray caster) asks which entries the
    // correction makes exact before it measures (their noise does not count), then says what its
    // measuring error came to: the row's estimate is that plus the correction's own terms.
    stages.exact_entries = [&](std::size_t k, std::uint32_t i) {
        NearAnalysis& a = analyses_[k];
        if (!a.done) {
            std::unique_ptr<NearFieldScratch> scratch = pools_->take(a.exact);
            corrector_.analyse(i, a, *scratch);
            pools_->give_back(std::move(scratch));
        }
        return std::span<const std::pair<std::uint32_t, double>>(a.exact);
    };
    stages.measured = [&](std::size_t k, std::uint32_t, double error, double rays) {
        analyses_[k].measured_error = error;
        analyses_[k].measured_rays = rays;
    };
    stages.finish = [&](std::size_t k, std::uint32_t i, SparseRow& row) {
        Stopwatch watch;
        NearAnalysis& a = analyses_[k];
        NearFieldStats local;
        // Whether light escapes, as measured: for a row not measured, its analytic sum.
        double measured = row.sum();
        if (a.skipped) {
            measured = 0;
            for (const auto& e : a.exact) measured += e.second;
        }
        local.inner_row_sum_min = measured;
        std::unique_ptr<NearFieldScratch> scratch = pools_->take();
        double estimate = 0;
        const bool sampled = sample && a.done && a.sampled;
        // Rows planned at 4 × 4 (occluder 2) that the inner provider ray-cast (fine_rows).
        const double cast_rays = sampled && a.occluder == 2 ? static_cast<double>(cast_fine_rays) : 0.0;
        SparseRow& inner = scratch->buffers().inner;
        inner = row;  // the row as measured (the buffer's capacity is reused)
        RowNoise noise;
        corrector_.correct(i, row, local, *scratch, &estimate, &a, sampled, cast_rays, &noise);
        // The tolerance's estimate: the correction's own terms (systematic: far field,
        // quadrature residual, rebalancing), plus the measuring error as the provider measured it
        // or, where it did not, as modelled: the largest entry's noise or the sum's, whichever
        // is larger. The sum's: its outline against the sky, and the entries replaced by exact
        // values, whose measured errors no longer cancel their neighbours' (RowNoise).
        double tolerance_estimate =
            a.measured_error >= 0 ? estimate + a.measured_error
                                  : estimate - noise.l1 +
                                        kNoiseDeviations * std::max(noise.max, std::sqrt(noise.sky * noise.sky + noise.replaced_sum_sq));
        // Accuracy by target: a row above it that its provider did not refine is measured again
        // by the refiners in turn (refine_with) until its estimate meets it: drawn again at a
        // finer resolution (its noise modelled at that pixel), then by rays, whose error is
        // measured. Each time the row is corrected as that measure's row.
        bool by_rays = false, by_redraw = false;
        const bool drawn = a.measured_error < 0 && !a.skipped && cast_rays == 0;
        for (const Refiner& refiner : refiners_) {
            if (a.skipped || a.measured_error >= 0 || tolerance_estimate <= refine_tolerance_) break;
            const std::uint32_t one[1] = {i};
            NearFieldStats discarded;  // the row's statistics are its first correction's
            if (refiner.pixel_delta_ff > 0) {
                if (!drawn) continue;  // a ray-cast row: no pixels to refine
                // The request of its first measure: the same plan and sender points.
                RowRequest request[1];
                request[0].plan = !sampled ? RowPlan::centre : a.occluder == 2 ? RowPlan::sampled_fine : RowPlan::sampled;
                if (sampled) sender_points(i, request[0]);
                refiner.provider->compute_rows_requested(one, request, [&](std::uint32_t, const SparseRow& r) { row = r; });
                inner = row;
                a.pixel_delta_ff = refiner.pixel_delta_ff;
                noise = RowNoise{};
                estimate = 0;
                corrector_.correct(i, row, discarded, *scratch, &estimate, &a, sampled, 0.0, &noise);
                tolerance_estimate = estimate - noise.l1 +
                                     kNoiseDeviations * std::max(noise.max, std::sqrt(noise.sky * noise.sky + noise.replaced_sum_sq));
                by_redraw = true;
                continue;
            }
            RowStages again;
            again.exact_entries = [&](std::size_t, std::uint32_t) {
                return std::span<const std::pair<std::uint32_t, double>>(a.exact);
            };
            again.measured = [&](std::size_t, std::uint32_t, double error, double rays) {
                a.measured_error = error;
                a.measured_rays = rays;
            };
            refiner.provider->compute_rows_staged(one, again, [&](std::uint32_t, const SparseRow& r) { row = r; });
            FFCUBE_CHECK_MSG(a.measured_error >= 0 && a.measured_rays > 0, "the refiner measured no error");
            inner = row;
            noise = RowNoise{};
            estimate = 0;
            corrector_.correct(i, row, discarded, *scratch, &estimate, &a, true, a.measured_rays, &noise);
            // Its own modelled noise out, its measured error in (as for the ray caster's rows).
            estimate -= noise.l1;
            tolerance_estimate = estimate + a.measured_error;
            by_rays = true;
        }
        if (by_redraw) rows_redrawn_.fetch_add(1, std::memory_order_relaxed);
        if (by_rays) rows_refined_.fetch_add(1, std::memory_order_relaxed);
        if (a.measured_error >= 0) estimate += a.measured_error;
        // The last check before the row leaves the layer: a corrected row out of range (an entry
        // below 0 or above 1, not finite, or a sum above 1 beyond its tolerance) is replaced by
        // the row as measured, which a hemicube or the rays make valid (ΔF sums of one or more
        // hemicubes with positive weights of sum at most 1). Its estimate grows by the change:
        // |measured − exact| ≤ |measured − corrected| + |corrected − exact|. A row made without
        // measuring (analytic) has none to fall back on: refused by name.
        const double tol = accuracy::row_range_tolerance(options_.keep_closed_rows, estimate);
        if (!accuracy::row_in_range(row.val, tol)) {
            if (a.skipped || !accuracy::row_in_range(inner.val, accuracy::kClosedRowTolerance))
                throw InputError(out_of_range_message(i, row, a.skipped));
            double moved = 0;
            std::size_t p = 0, q = 0;
            while (p < row.nnz() || q < inner.nnz()) {
                if (q == inner.nnz() || (p < row.nnz() && row.col[p] < inner.col[q])) moved += std::abs(row.val[p++]);
                else if (p == row.nnz() || inner.col[q] < row.col[p]) moved += std::abs(inner.val[q++]);
                else moved += std::abs(row.val[p++] - inner.val[q++]);
            }
            estimate = std::isfinite(moved) ? estimate + moved : moved;
            tolerance_estimate = std::isfinite(moved) ? tolerance_estimate + moved : moved;
            std::swap(row, inner);
            ++local.rows_recomputed_out_of_range;
            pools_->note_out_of_range(i);
        }
        pools_->give_back(std::move(scratch));
        // The row's figures go with it to every sink (SparseRow::side).
        row.side.error = static_cast<float>(estimate);
        row.side.tolerance_error = static_cast<float>(std::max(tolerance_estimate, 0.0));
        row.side.measure = by_rays     ? RowMeasure::refined
                          : by_redraw ? RowMeasure::redrawn
                          : a.skipped ? RowMeasure::analytic
                          : !sampled ? RowMeasure::centre
                          : a.occluder == 2 ? RowMeasure::sampled_touching
                          : a.refused_sampled > 0 ? RowMeasure::sampled_near_pair
                          : a.occluder == 1 ? RowMeasure::sampled_occluder
                          : a.sampled_unproven ? RowMeasure::sampled_unproven
                                               : RowMeasure::sampled_near_pair;
        // Give the analysis's buffer back: with the far field it holds up to a whole row, and
        // every row of the call has a slot (n² entries if none were freed: 225 MB for 3,744
        // patches); the pool holds only as many as were in flight at once.
        pools_->recycle(a.exact);
        a = NearAnalysis{};
        local.seconds = watch.seconds();
        pools_->add(stats_, local);
    };
    pools_->out_of_range.clear();
    inner_.compute_rows_staged(rows, stages, sink);
    warn_out_of_range();
}

std::string CorrectedRowProvider::patch_name(std::uint32_t i) const {
    const Patch& p = scene_.patches[i];
    return fmt::format("patch {} (object '{}')", i, p.object < scene_.objects.size() ? scene_.objects[p.object] : "?");
}

std::string CorrectedRowProvider::out_of_range_message(std::uint32_t i, const SparseRow& row, bool made_analytically) const {
    double sum = 0, least = INFINITY, most = -INFINITY;
    for (const double v : row.val) sum += v, least = std::min(least, v), most = std::max(most, v);
    return fmt::format(
        "{}: the near-field correction made its row out of range (sum {:.6g}, entries from {:.3g} to {:.3g}) and {}: the "
        "geometry around it is not one ffcube can measure (faces that pass through or lie inside others?); --correct "
        "none or --method raycast measure it without the correction",
        patch_name(i), sum, least, most,
        made_analytically ? "the row was made without measuring, so there is no measured row to fall back on"
                 : "the row as measured is out of range too");
}

// One warning per call, naming the first rows in row order (the same whatever the threads).
void CorrectedRowProvider::warn_out_of_range() {
    std::vector<std::uint32_t>& rows = pools_->out_of_range;
    if (rows.empty()) return;
    std::sort(rows.begin(), rows.end());
    std::string list;
    for (std::size_t k = 0; k < rows.size() && k < 3; ++k) list += (k ? ", " : "") + patch_name(rows[k]);
    log_warning(fmt::format("{} row{} out of range after the near-field correction (an entry below 0 or above 1, or a sum "
                            "above 1 beyond the row's tolerance) handed on as measured, uncorrected: {}{}",
                            rows.size(), rows.size() == 1 ? "" : "s", list, rows.size() > 3 ? ", ..." : ""));
    rows.clear();
}

}  // namespace ffcube
