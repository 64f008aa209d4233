// Rows carried between adaptive levels (src/pipeline/row_reuse.hpp): only the elements' rows are
// measured; a kept patch's row keeps its entries, and the column of a split patch is shared among its
// elements by reciprocity with their measured rows, keeping the row's sum.
#include <gtest/gtest.h>

#include <vector>

#include "ffcube/scene/refine.hpp"
#include "pipeline/row_reuse.hpp"
#include "support/scenes.hpp"

namespace ffcube {
namespace {

// Counts the rows asked of it.
class Counting final : public RowProvider {
public:
    explicit Counting(const CsrMatrix& m) : inner_(m) {}
    std::uint32_t size() const override { return inner_.size(); }
    std::string name() const override { return "counting"; }
    void compute_rows(std::span<const std::uint32_t> rows, const RowSink& sink) override {
        asked.insert(asked.end(), rows.begin(), rows.end());
        inner_.compute_rows(rows, sink);
    }
    std::vector<std::uint32_t> asked;

private:
    MatrixRowProvider inner_;
};

// Two opposed unit squares one patch each (floor 0 facing up, ceiling 1 facing down); the previous
// level's rows F_01 = F_10 = 0.2; the ceiling is split 2 × 2 into elements 1..4 of area 1/4.
struct TwoSquares {
    Scene coarse = test::make_scene({test::square_z("floor", 0.0, true), test::square_z("ceiling", 1.0, false)}, 1.0);
    std::vector<std::uint32_t> split{1, 2};
    RefinedScene fine = refine_patches(coarse, split);
    LevelRows previous() const {
        LevelRows r;
        r.rows.resize(2);
        r.rows[0].col = {1};
        r.rows[0].val = {0.2};
        r.rows[1].col = {0};
        r.rows[1].val = {0.2};
        r.present = {true, true};
        return r;
    }
    // The elements' measured rows: element c sends F_c0 to the floor (values exact in float).
    CsrMatrix measured(std::vector<float> to_floor) const {
        CsrMatrix m(5);
        m.append_row(std::vector<std::uint32_t>{}, std::vector<float>{});  // row 0: never asked
        for (std::uint32_t c = 1; c <= 4; ++c) {
            const std::vector<std::uint32_t> col = to_floor[c - 1] > 0 ? std::vector<std::uint32_t>{0} : std::vector<std::uint32_t>{};
            const std::vector<float> val = to_floor[c - 1] > 0 ? std::vector<float>{to_floor[c - 1]} : std::vector<float>{};
            m.append_row(col, val);
        }
        return m;
    }
};

std::vector<SparseRow> all_rows(RowProvider& p) {
    std::vector<SparseRow> out(p.size());
    std::vector<std::uint32_t> rows;
    for (std::uint32_t i = 0; i < p.size(); ++i) rows.push_back(i);
    p.compute_rows(rows, [&](std::uint32_t i, const SparseRow& r) { out[i] = r; });
    return out;
}

TEST(RowReuse, OnlyElementsAreMeasuredAndASplitColumnIsSharedByReciprocity) {
    const TwoSquares s;
    ASSERT_EQ(s.fine.scene.size(), 5u);
    ASSERT_EQ(s.fine.parent, (std::vector<std::uint32_t>{0, 1, 1, 1, 1}));
    const CsrMatrix m = s.measured({0.125f, 0.25f, 0.375f, 0.5f});
    Counting inner(m);
    ReusedRowProvider p(s.fine.scene, inner, s.fine.parent, s.split, s.previous());
    const std::vector<SparseRow> rows = all_rows(p);
    EXPECT_EQ(inner.asked, (std::vector<std::uint32_t>{1, 2, 3, 4}));
    EXPECT_EQ(p.rows_measured(), 4u);
    EXPECT_EQ(p.rows_reused(), 1u);
    // Row 0: F_0c = F_01 · A_c F_c0 / Σ A_c' F_c'0, equal areas: 0.2 · F_c0 / 1.25; the sum stays 0.2.
    ASSERT_EQ(rows[0].col, (std::vector<std::uint32_t>{1, 2, 3, 4}));
    const double to_floor[4] = {0.125, 0.25, 0.375, 0.5};
    double sum = 0.0;
    for (int c = 0; c < 4; ++c) {
        EXPECT_NEAR(rows[0].val[c], 0.2 * to_floor[c] / 1.25, 1e-15);
        sum += rows[0].val[c];
    }
    EXPECT_NEAR(sum, 0.2, 1e-15);
    // The elements' rows are the measured ones.
    for (std::uint32_t c = 1; c <= 4; ++c) {
        ASSERT_EQ(rows[c].nnz(), 1u);
        EXPECT_EQ(rows[c].val[0], to_floor[c - 1]);
    }
}

TEST(RowReuse, AreaSharesWhenNoElementSeesThePatchAndEverythingMeasuredWithoutPreviousRows) {
    const TwoSquares s;
    const CsrMatrix m = s.measured({0.0f, 0.0f, 0.0f, 0.0f});
    Counting inner(m);
    ReusedRowProvider p(s.fine.scene, inner, s.fine.parent, s.split, s.previous());
    const std::vector<SparseRow> rows = all_rows(p);
    ASSERT_EQ(rows[0].nnz(), 4u);
    for (int c = 0; c < 4; ++c) EXPECT_NEAR(rows[0].val[c], 0.05, 1e-15);  // 0.2 × (1/4) / 1
    // No previous rows (level 0, or AdaptiveOptions::reuse_rows off): every row is measured.
    Counting fresh(m);
    ReusedRowProvider q(s.fine.scene, fresh, s.fine.parent, s.split, LevelRows{});
    all_rows(q);
    EXPECT_EQ(fresh.asked, (std::vector<std::uint32_t>{0, 1, 2, 3, 4}));
    EXPECT_EQ(q.rows_reused(), 0u);
}

}  // namespace
}  // namespace ffcube
