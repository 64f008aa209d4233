#include "ffcube/formfactor/row_provider.hpp"

#include <algorithm>
#include <numeric>
#include <vector>

#include "ffcube/core/error.hpp"

namespace ffcube {

void RowProvider::compute_row(std::uint32_t i, SparseRow& out) {
    const std::uint32_t rows[1] = {i};
    compute_rows(rows, [&](std::uint32_t, const SparseRow& r) { out = r; });
}

void RowProvider::compute_rows_requested(std::span<const std::uint32_t> rows, std::span<const RowRequest> requests,
                                         const RowSink& sink) {
    FFCUBE_CHECK_MSG(requests.size() == rows.size(), "compute_rows_requested: one request per row");
    compute_rows(rows, sink);
}

void RowProvider::compute_rows_planned(std::span<const std::uint32_t> rows, std::span<const RowPlan> plans,
                                       const RowSink& sink) {
    FFCUBE_CHECK_MSG(plans.size() == rows.size(), "compute_rows_planned: one plan per row");
    std::vector<RowRequest> requests(plans.size());
    for (std::size_t k = 0; k < plans.size(); ++k) requests[k].plan = plans[k];
    compute_rows_requested(rows, requests, sink);
}

void RowProvider::compute_rows_staged(std::span<const std::uint32_t> rows, const RowStages& stages,
                                      const RowSink& sink) {
    const bool planned = stages.plan && can_sample_sender();
    // Batches bound the requests held at once; a plan's own state (the caller's) is per row anyway.
    constexpr std::size_t kBatch = 64;
    std::vector<RowRequest> requests;
    // The row as finish works on it: this thread's, kept from call to call (no allocation per
    // call once it has grown to the longest row).
    thread_local SparseRow row;
    std::size_t k = 0;
    const RowSink finish = [&](std::uint32_t i, const SparseRow& measured) {
        if (!stages.finish) {
            sink(i, measured);
            ++k;
            return;
        }
        row = measured;
        stages.finish(k++, i, row);
        sink(i, row);
    };
    for (std::size_t begin = 0; begin < rows.size(); begin += kBatch) {
        const std::span<const std::uint32_t> batch = rows.subspan(begin, std::min(kBatch, rows.size() - begin));
        if (planned) {
            requests.resize(batch.size());
            for (std::size_t p = 0; p < batch.size(); ++p) {
                requests[p].reset();
                stages.plan(begin + p, batch[p], requests[p]);
                // This path has no second engine: the driver hands rows for the ray caster only to a
                // provider that runs the stages itself (HemicubeRowProvider).
                FFCUBE_CHECK_MSG(requests[p].engine == RowEngine::provider,
                                 "RowProvider::compute_rows_staged: a row for the ray caster on the default path");
            }
            compute_rows_requested(batch, requests, finish);
        } else {
            compute_rows(batch, finish);
        }
    }
}

void MatrixRowProvider::compute_rows(std::span<const std::uint32_t> rows, const RowSink& sink) {
    SparseRow tmp;
    for (std::uint32_t i : rows) {
        const RowView v = m_.row(i);
        tmp.col.assign(v.col.begin(), v.col.end());
        tmp.val.assign(v.val.begin(), v.val.end());
        sink(i, tmp);
    }
}

RowSink ObservingRowProvider::observing(const RowSink& sink) {
    return [this, &sink](std::uint32_t i, const SparseRow& row) { sink(i, observe(i, row)); };
}

void ObservingRowProvider::compute_rows(std::span<const std::uint32_t> rows, const RowSink& sink) {
    inner_.compute_rows(rows, observing(sink));
}

void ObservingRowProvider::compute_rows_requested(std::span<const std::uint32_t> rows,
                                                  std::span<const RowRequest> requests, const RowSink& sink) {
    inner_.compute_rows_requested(rows, requests, observing(sink));
}

void ObservingRowProvider::compute_rows_staged(std::span<const std::uint32_t> rows, const RowStages& stages,
                                               const RowSink& sink) {
    inner_.compute_rows_staged(rows, stages, observing(sink));
}

LeadingRowProvider::LeadingRowProvider(RowProvider& inner, std::uint32_t n) : ObservingRowProvider(inner), n_(n) {
    FFCUBE_CHECK_MSG(n <= inner.size(), "LeadingRowProvider: more rows than the inner provider has");
}

const SparseRow& LeadingRowProvider::observe(std::uint32_t i, const SparseRow& full) {
    FFCUBE_CHECK(i < n_);
    // Columns are increasing: the kept ones are a prefix.
    const auto keep = static_cast<std::size_t>(std::lower_bound(full.col.begin(), full.col.end(), n_) - full.col.begin());
    double cut = 0.0;
    for (std::size_t k = keep; k < full.col.size(); ++k) cut += full.val[k];
    if (keep == full.col.size() && full.side.obstructed == cut) return full;  // nothing cut (cut = +0.0)
    row_.col.assign(full.col.begin(), full.col.begin() + static_cast<std::ptrdiff_t>(keep));
    row_.val.assign(full.val.begin(), full.val.begin() + static_cast<std::ptrdiff_t>(keep));
    row_.side = full.side;
    row_.side.obstructed = cut;
    return row_;
}

CsrMatrix compute_all_rows(RowProvider& provider, RowLedger* ledger) {
    const std::uint32_t n = provider.size();
    std::vector<std::uint32_t> all(n);
    std::iota(all.begin(), all.end(), 0u);
    CsrMatrix m(n);
    if (ledger) ledger->resize(n);
    provider.compute_rows(all, [&](std::uint32_t i, const SparseRow& r) {
        FFCUBE_CHECK(i == m.rows_filled());
        m.append_row(r);
        if (ledger) ledger->note(i, r.side);
    });
    return m;
}

}  // namespace ffcube
