// Rows allocate nothing in the steady state: NearFieldCorrector::correct and analyse work in the
// caller's NearFieldScratch, and CorrectedRowProvider keeps its scratch spaces and analysis
// buffers across rows. Counted with a replaced global operator new (for this test executable).
//
// The scene is two parallel plates 120 sizes apart with the far field on: every row goes
// through the grid query, the far field, the merge and the estimate, and calls no geometry/
// function that allocates on its own (ff_polygon_polygon, ff_point_polygon and patch_quadrature
// make their own vectors: near pairs and the sender quadrature still allocate there).
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <cstdint>
#include <cstdlib>
#include <new>
#include <numeric>
#include <vector>

#include "ffcube/accuracy/near_field.hpp"
#include "support/scenes.hpp"

// GCC cannot see that these replace the global operators, and warns that free() meets new.
#pragma GCC diagnostic ignored "-Wmismatched-new-delete"

namespace {
std::atomic<std::size_t> g_allocations{0};
}  // namespace

void* operator new(std::size_t n) {
    g_allocations.fetch_add(1, std::memory_order_relaxed);
    if (void* p = std::malloc(n ? n : 1)) return p;
    throw std::bad_alloc();
}
void* operator new[](std::size_t n) {
    g_allocations.fetch_add(1, std::memory_order_relaxed);
    if (void* p = std::malloc(n ? n : 1)) return p;
    throw std::bad_alloc();
}
void operator delete(void* p) noexcept { std::free(p); }
void operator delete[](void* p) noexcept { std::free(p); }
void operator delete(void* p, std::size_t) noexcept { std::free(p); }
void operator delete[](void* p, std::size_t) noexcept { std::free(p); }

namespace ffcube {
namespace {

Scene far_plates() {
    return test::make_scene({test::square_z("low", 0, true), test::square_z("high", 20, false)}, 0.17);
}

NearFieldOptions far_on() {
    NearFieldOptions o;
    o.far_field = NearFieldOptions::FarField::on;
    return o;
}

// Inner rows: every patch of the other plate at 1e-3 (the corrector merges them with the far
// field's values).
std::vector<SparseRow> inner_rows(const Scene& s) {
    std::vector<SparseRow> rows(s.size());
    for (std::uint32_t i = 0; i < s.size(); ++i)
        for (std::uint32_t j = 0; j < s.size(); ++j)
            if (s.patches[j].object != s.patches[i].object) {
                rows[i].col.push_back(j);
                rows[i].val.push_back(1e-3);
            }
    return rows;
}

TEST(Scratch, CorrectAllocatesNothingPerRow) {
    const Scene s = far_plates();
    ASSERT_EQ(s.size(), 72u);
    const NearFieldCorrector c(s, far_on());
    ASSERT_GT(c.far_field_planes(), 0u);
    const std::vector<SparseRow> inner = inner_rows(s);
    NearFieldScratch scratch;
    NearAnalysis analysis;
    SparseRow row;
    NearFieldStats stats;
    const auto pass = [&] {
        for (std::uint32_t i = 0; i < s.size(); ++i) {
            c.analyse(i, analysis, scratch);
            row = inner[i];
            double estimate = 0;
            c.correct(i, row, stats, scratch, &estimate, &analysis);
        }
    };
    pass();  // the buffers grow to the largest row
    pass();
    const std::size_t before = g_allocations.load();
    pass();
    EXPECT_EQ(g_allocations.load() - before, 0u);
    EXPECT_EQ(stats.far_entries, 3 * 72u * 36u);  // the rows did go through the far field
    EXPECT_EQ(stats.rows_untouched, 0u);
}

// An inner provider that follows every row's plan (as the hemicube does) and keeps its row
// buffer across calls.
class PlanningProvider final : public RowProvider {
public:
    explicit PlanningProvider(std::vector<SparseRow> rows) : rows_(std::move(rows)) {}
    std::uint32_t size() const override { return static_cast<std::uint32_t>(rows_.size()); }
    std::string name() const override { return "planning"; }
    void compute_rows(std::span<const std::uint32_t> rows, const RowSink& sink) override {
        for (std::uint32_t i : rows) {
            buffer_ = rows_[i];
            sink(i, buffer_);
        }
    }
    bool can_sample_sender() const override { return true; }
    void compute_rows_requested(std::span<const std::uint32_t> rows, std::span<const RowRequest> requests,
                                const RowSink& sink) override {
        for (std::size_t pos = 0; pos < rows.size(); ++pos) {
            const RowPlan p = requests[pos].plan;
            if (p == RowPlan::skip) {
                buffer_.clear();
            } else {
                buffer_ = rows_[rows[pos]];
            }
            ++plans_[static_cast<std::size_t>(p)];
            sink(rows[pos], buffer_);
        }
    }
    std::array<std::size_t, 3> plans_{};

private:
    std::vector<SparseRow> rows_;
    SparseRow buffer_;
};

// Through CorrectedRowProvider, with plans (sampled) or not: a call allocates a fixed few times,
// never per row.
class CorrectedRowProviderScratch : public testing::TestWithParam<bool> {};

TEST_P(CorrectedRowProviderScratch, AllocatesNothingPerRow) {
    const bool planned = GetParam();
    const Scene s = far_plates();
    PlanningProvider inner(inner_rows(s));
    NearFieldOptions o = far_on();
    o.skip_complete_rows = false;  // measure every row: the merge runs on each
    o.sub_hemicubes = planned;     // false: rows are analysed when they arrive
    CorrectedRowProvider corrected(s, inner, o);
    std::vector<std::uint32_t> all(s.size());
    std::iota(all.begin(), all.end(), 0u);
    double sum = 0;
    const RowSink sink = [&](std::uint32_t, const SparseRow& r) { sum += r.sum(); };
    corrected.compute_rows(all, sink);  // the buffers grow
    corrected.compute_rows(all, sink);
    // The pools hold as many scratch spaces and analysis buffers as were ever in use at once, and
    // which buffer serves which row depends on the planning threads' timing: on a loaded machine a
    // call may still meet a new high-water mark (a new buffer, or one growing to the largest row:
    // 29 allocations seen once in 60 runs beside three busy loops). Such growth happens once per
    // buffer and cannot recur, whereas a per-row allocation recurs in every call: so the count of
    // a call is the least over five calls.
    const auto count = [&](std::size_t rows) {
        std::size_t least = SIZE_MAX;
        for (int k = 0; k < 5; ++k) {
            const std::size_t before = g_allocations.load();
            corrected.compute_rows(std::span<const std::uint32_t>(all).first(rows), sink);
            least = std::min(least, g_allocations.load() - before);
        }
        return least;
    };
    const std::size_t a = count(all.size()), b = count(all.size() / 4);
    // This inner provider keeps RowProvider's own compute_rows_staged (plans and corrections on
    // the calling thread, in batches of 64 rows): a few allocations per call (the sink's
    // std::function; with plans, the plan list), none per row or per batch.
    EXPECT_EQ(a, b) << "per " << all.size() / 4 << "-row call " << b << ", per " << all.size() << "-row call " << a;
    EXPECT_LE(a, 4u);
    EXPECT_EQ(inner.plans_[static_cast<std::size_t>(RowProvider::RowPlan::centre)], planned ? (2 + 5) * 72u + 5 * 18u : 0u);
    EXPECT_EQ(corrected.retained_analysis_entries(), 0u);
    EXPECT_EQ(corrected.stats().far_entries, ((2 + 5) * 72u + 5 * 18u) * 36u);
    EXPECT_GT(sum, 0.0);
}

INSTANTIATE_TEST_SUITE_P(Scratch, CorrectedRowProviderScratch, testing::Bool());

}  // namespace
}  // namespace ffcube
