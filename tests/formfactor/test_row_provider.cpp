// The row-provider wrappers (formfactor/row_provider.hpp): ObservingRowProvider forwards every
// entry point and shows each row once; LeadingRowProvider cuts rows on top of it. And the one
// rule of a stored row's sum (formfactor/sparse.hpp): SparseRow::stored_sum is RowView::sum.
#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "ffcube/formfactor/row_provider.hpp"

namespace ffcube {
namespace {

using RowPlan = RowProvider::RowPlan;

TEST(StoredSum, IsRowViewSumBitForBit) {
    // 1 and three entries of 3e-8 (< half of float's spacing at 1, 6e-8): summed in float the
    // small ones vanish (1.0f); the entries as double are not the float entries a CsrMatrix keeps.
    const SparseRow row{{0, 2, 5, 7}, {1.0, 3e-8, 3e-8, 3e-8}};
    CsrMatrix F(8);
    F.append_row(row);
    const double stored = row.stored_sum();
    EXPECT_EQ(stored, F.row(0).sum());  // the same double, not merely close
    const double f = static_cast<float>(3e-8);
    EXPECT_EQ(stored, ((1.0 + f) + f) + f);  // floats, summed in double, in column order
    float in_float = 0.0f;
    for (const double v : row.val) in_float += static_cast<float>(v);
    EXPECT_EQ(in_float, 1.0f);
    EXPECT_NE(stored, static_cast<double>(in_float));
    EXPECT_NE(stored, row.sum());  // the double entries: another sum
}

// Five rows; row i has entries at columns i+1 .. 4 (value 0.1 (k+1)). Records which entry point
// it was called through, and runs the staged stages itself (as a threaded provider would).
class Recording final : public RowProvider {
public:
    std::uint32_t size() const override { return 5; }
    std::string name() const override { return "recording"; }
    bool can_sample_sender() const override { return true; }
    void compute_rows(std::span<const std::uint32_t> rows, const RowSink& sink) override {
        calls.push_back("rows");
        for (const std::uint32_t i : rows) sink(i, row(i));
    }
    void compute_rows_requested(std::span<const std::uint32_t> rows, std::span<const RowRequest> requests,
                                const RowSink& sink) override {
        calls.push_back("planned");
        seen_plans.clear();
        for (const RowRequest& r : requests) seen_plans.push_back(r.plan);
        for (const std::uint32_t i : rows) sink(i, row(i));
    }
    void compute_rows_staged(std::span<const std::uint32_t> rows, const RowStages& stages, const RowSink& sink) override {
        calls.push_back("staged");
        for (std::size_t k = 0; k < rows.size(); ++k) {
            RowRequest request;
            stages.plan(k, rows[k], request);
            seen_plans.push_back(request.plan);
            SparseRow r = row(rows[k]);
            stages.finish(k, rows[k], r);
            sink(rows[k], r);
        }
    }
    static SparseRow row(std::uint32_t i) {
        SparseRow r;
        for (std::uint32_t j = i + 1; j < 5; ++j) r.col.push_back(j), r.val.push_back(0.1 * (j + 1));
        return r;
    }
    std::vector<std::string> calls;
    std::vector<RowPlan> seen_plans;
};

class Counting final : public ObservingRowProvider {
public:
    using ObservingRowProvider::ObservingRowProvider;
    std::vector<std::uint32_t> observed;

private:
    const SparseRow& observe(std::uint32_t i, const SparseRow& row) override {
        EXPECT_EQ(row.col, Recording::row(i).col);
        observed.push_back(i);
        return row;
    }
};

// What a sink got: (i, nnz) per row, in order.
struct Received {
    std::vector<std::uint32_t> rows;
    std::vector<std::size_t> nnz;
    std::vector<double> obstructed;  // each row's side.obstructed
    RowSink sink() {
        return [this](std::uint32_t i, const SparseRow& r) {
            rows.push_back(i), nnz.push_back(r.nnz()), obstructed.push_back(r.side.obstructed);
        };
    }
};

const std::vector<std::uint32_t> kRows{3, 0, 4, 1};
const std::vector<std::size_t> kNnz{1, 4, 0, 3};  // row i has 4 − i entries

TEST(ObservingRowProvider, ForwardsEveryEntryPointAndObservesEveryRowOnce) {
    Recording inner;
    Counting c(inner);
    EXPECT_EQ(c.size(), 5u);
    EXPECT_EQ(c.name(), "recording");
    EXPECT_TRUE(c.can_sample_sender());
    const std::vector<RowPlan> plans{RowPlan::sampled, RowPlan::centre, RowPlan::skip, RowPlan::sampled_fine};
    Received a, b, s;
    c.compute_rows(kRows, a.sink());
    c.compute_rows_planned(kRows, plans, b.sink());
    EXPECT_EQ(inner.seen_plans, plans);
    inner.seen_plans.clear();
    std::vector<std::uint32_t> finished;
    RowProvider::RowStages stages{[&](std::size_t k, std::uint32_t, RowProvider::RowRequest& r) { r.plan = plans[k]; },
                                  [&](std::size_t, std::uint32_t i, SparseRow&) { finished.push_back(i); }};
    c.compute_rows_staged(kRows, stages, s.sink());
    // Each call reached the inner provider through the same entry point, once.
    EXPECT_EQ(inner.calls, (std::vector<std::string>{"rows", "planned", "staged"}));
    EXPECT_EQ(inner.seen_plans, plans);
    EXPECT_EQ(finished, kRows);
    for (const Received* r : {&a, &b, &s}) {
        EXPECT_EQ(r->rows, kRows);
        EXPECT_EQ(r->nnz, kNnz);
    }
    // Every row observed exactly once per call, in list order.
    std::vector<std::uint32_t> want;
    for (int k = 0; k < 3; ++k) want.insert(want.end(), kRows.begin(), kRows.end());
    EXPECT_EQ(c.observed, want);
}

TEST(LeadingRowProvider, CutsRowsOnEveryEntryPointAndFinishSeesTheCutRow) {
    Recording inner;
    LeadingRowProvider lead(inner, 3);
    EXPECT_EQ(lead.size(), 3u);
    const std::vector<std::uint32_t> rows{2, 0};
    Received a;
    lead.compute_rows(rows, a.sink());
    // Row 0: columns 1..4 → 1, 2 kept, 0.4 + 0.5 cut; row 2: columns 3, 4 all cut (0.4 + 0.5).
    EXPECT_EQ(a.nnz, (std::vector<std::size_t>{0, 2}));
    // Each row carries what was cut from it (rows 2, 0 in list order).
    ASSERT_EQ(a.obstructed.size(), 2u);
    EXPECT_DOUBLE_EQ(a.obstructed[0], 0.4 + 0.5);
    EXPECT_DOUBLE_EQ(a.obstructed[1], 0.4 + 0.5);
    lead.compute_rows(std::vector<std::uint32_t>{1}, a.sink());
    EXPECT_EQ(a.nnz[2], 1u);
    EXPECT_DOUBLE_EQ(a.obstructed[2], 0.4 + 0.5);  // row 1: column 2 kept, 3 and 4 cut
    // Staged: not forwarded (the inner finish would see uncut rows) but planned on this thread.
    std::vector<std::size_t> finished_nnz;
    RowProvider::RowStages stages{[](std::size_t, std::uint32_t, RowProvider::RowRequest& r) { r.plan = RowPlan::sampled; },
                                  [&](std::size_t, std::uint32_t, SparseRow& r) { finished_nnz.push_back(r.nnz()); }};
    Received s;
    lead.compute_rows_staged(rows, stages, s.sink());
    EXPECT_EQ(inner.calls, (std::vector<std::string>{"rows", "rows", "planned"}));
    EXPECT_EQ(finished_nnz, (std::vector<std::size_t>{0, 2}));
    EXPECT_EQ(s.nnz, (std::vector<std::size_t>{0, 2}));
    EXPECT_EQ(s.obstructed, std::vector<double>(a.obstructed.begin(), a.obstructed.begin() + 2)) << "staged rows carry their cut shares too";
}

}  // namespace
}  // namespace ffcube
