// CorrectedRowProvider: wraps a RowProvider and corrects each row as it is handed on, planning
// each row (sub-hemicubes, skip) from its analysis before the inner provider is asked for it. Owns the
// scratch space the corrector works in, so that rows allocate nothing in the steady state.
#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <atomic>
#include <future>
#include <mutex>
#include <thread>

#include "accuracy/scratch.hpp"
#include "ffcube/accuracy/near_field.hpp"
#include "ffcube/core/error.hpp"
#include "ffcube/core/timer.hpp"

namespace ffcube {

// Scratch spaces and analysis buffers, taken and given back under a lock by the plan callbacks
// (several at once, on the inner provider's threads) and the sink. There are as many as were
// ever in use at once: the inner provider's threads, and its window of rows in flight.
struct CorrectedRowProvider::Pools {
    using Entries = std::vector<std::pair<std::uint32_t, double>>;
    NearFieldScratch sink;  // the rows as they arrive, on the calling thread
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
    void give_back(std::unique_ptr<NearFieldScratch> s) {
        const std::lock_guard lock(mutex);
        scratch.push_back(std::move(s));
    }
    // Keeps exact's buffer for a later analysis (when it has one: an analysis made by correct()
    // itself lives in the sink's scratch, and the slot's is empty).
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
      corrector_(scene, options),
      options_(options),
      pools_(std::make_unique<Pools>()),
      plan_threads_(std::max(1u, std::thread::hardware_concurrency())) {
    if (inner.size() != scene.size())
        throw InputError(fmt::format("near-field correction: the provider has {} rows, the scene {} patches", inner.size(),
                                     scene.size()));
}

CorrectedRowProvider::~CorrectedRowProvider() = default;

void CorrectedRowProvider::compute_rows(std::span<const std::uint32_t> rows, const RowSink& sink) {
    // Near analysis per listed row, made when its row is planned (below: each slot is written
    // once, by one planning thread, before its row is asked for) or, without plans, when the row
    // arrives.
    analyses_.assign(rows.size(), NearAnalysis{});
    std::size_t position = 0;
    const bool sample = options_.sub_hemicubes && inner_.can_sample_sender();
    const RowSink correct_row = [&](std::uint32_t i, const SparseRow& row) {
        Stopwatch watch;
        const std::size_t pos = position++;
        NearAnalysis& a = analyses_[pos];
        // Whether light escapes, as measured: for a row not measured, its analytic sum.
        double measured = row.sum();
        if (a.skipped) {
            measured = 0;
            for (const auto& e : a.exact) measured += e.second;
        }
        stats_.inner_row_sum_min = std::min(stats_.inner_row_sum_min, measured);
        scratch_ = row;
        double estimate = 0;
        const bool sampled = sample && a.done && a.sampled;
        corrector_.correct(i, scratch_, stats_, pools_->sink, &estimate, &a, sampled);
        if (row_error_.size() != inner_.size()) row_error_.assign(inner_.size(), NAN);
        row_error_[i] = static_cast<float>(estimate);
        if (row_measure_.size() != inner_.size()) row_measure_.assign(inner_.size(), RowMeasure::not_computed);
        row_measure_[i] = a.skipped ? RowMeasure::analytic
                          : !sampled ? RowMeasure::centre
                          : a.occluder == 2 ? RowMeasure::sampled_touching
                          : a.refused > 0   ? RowMeasure::sampled_near_pair
                          : a.occluder == 1 ? RowMeasure::sampled_occluder
                          : a.sampled_unproven ? RowMeasure::sampled_unproven
                                            : RowMeasure::sampled_near_pair;
        // Give the analysis's buffer back: with the far field it holds up to a whole row, and
        // every row of the call has a slot (n² entries if none were freed: 225 MB for 3,744
        // patches); the pool holds only as many as were in flight at once.
        pools_->recycle(a.exact);
        a = NearAnalysis{};
        stats_.seconds += watch.seconds();
        sink(i, scratch_);
    };
    if (!sample) {
        inner_.compute_rows(rows, correct_row);
        return;
    }
    // Rows with a near pair that may be occluded are measured by sub-hemicubes at the sender's
    // quadrature points (the pair keeps a value with its own visibility and sender quadrature);
    // rows whose every pair is known are not measured. Each row's plan comes from its analysis,
    // worked out here before the inner provider is asked: in batches, the next batch's analyses
    // (on this machine's cores) overlapping the inner provider's work on the current one. A plan
    // depends only on its row, so the rows do not depend on the batching or the thread count.
    plans_.assign(rows.size(), RowPlan::centre);
    const auto plan_batch = [&](std::size_t begin, std::size_t end) {
        if (end <= begin) return;  // no rows (e.g. a resumed checkpoint that has them all)
        std::atomic<std::size_t> next{begin};
        const auto work = [&] {
            for (std::size_t pos; (pos = next++) < end;) {
                NearAnalysis& a = analyses_[pos];
                std::unique_ptr<NearFieldScratch> scratch = pools_->take(a.exact);
                plans_[pos] = corrector_.plan_row(rows[pos], a, *scratch);
                pools_->give_back(std::move(scratch));
            }
        };
        const std::size_t helpers = std::min<std::size_t>(plan_threads_, end - begin) - 1;
        std::vector<std::jthread> threads;
        threads.reserve(helpers);
        for (std::size_t t = 0; t < helpers; ++t) threads.emplace_back(work);
        work();
    };
    const std::size_t n = rows.size();
    plan_batch(0, std::min(kPlanBatch, n));
    for (std::size_t begin = 0; begin < n; begin += kPlanBatch) {
        const std::size_t end = std::min(begin + kPlanBatch, n);
        // Destroyed (joined) before this iteration ends, also when the inner provider throws.
        std::future<void> next_batch;
        if (end < n) next_batch = std::async(std::launch::async, plan_batch, end, std::min(end + kPlanBatch, n));
        inner_.compute_rows_planned(rows.subspan(begin, end - begin), std::span(plans_).subspan(begin, end - begin),
                                    correct_row);
        if (next_batch.valid()) next_batch.get();
    }
}

}  // namespace ffcube
