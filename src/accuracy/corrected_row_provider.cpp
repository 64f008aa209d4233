// CorrectedRowProvider: wraps a RowProvider and corrects each row as it is handed on, planning
// each row (sub-hemicubes, skip) from its analysis when the inner provider asks. Owns the
// scratch space the corrector works in, so that rows allocate nothing in the steady state.
#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <mutex>

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
    : inner_(inner), corrector_(scene, options), options_(options), pools_(std::make_unique<Pools>()) {
    if (inner.size() != scene.size())
        throw InputError(fmt::format("near-field correction: the provider has {} rows, the scene {} patches", inner.size(),
                                     scene.size()));
}

CorrectedRowProvider::~CorrectedRowProvider() = default;

void CorrectedRowProvider::compute_rows(std::span<const std::uint32_t> rows, const RowSink& sink) {
    // Near analysis per listed row, made when the inner provider asks how to make the row (from
    // its own threads: each slot is written once, by one of them, before its row exists) or,
    // failing that, when the row arrives.
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
        corrector_.correct(i, scratch_, stats_, pools_->sink, &estimate, &a, sample && a.done && a.refused > 0);
        if (row_error_.size() != inner_.size()) row_error_.assign(inner_.size(), NAN);
        row_error_[i] = static_cast<float>(estimate);
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
    // quadrature points: the pair keeps a value with its own visibility and sender quadrature.
    inner_.compute_rows_sampled(
        rows,
        [&](std::size_t pos) {
            NearAnalysis& a = analyses_[pos];
            std::unique_ptr<NearFieldScratch> scratch = pools_->take(a.exact);
            const RowPlan plan = corrector_.plan_row(rows[pos], a, *scratch);
            pools_->give_back(std::move(scratch));
            return plan;
        },
        correct_row);
}

}  // namespace ffcube
