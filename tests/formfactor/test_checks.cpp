// Matrix checks: the reciprocity figure against values worked out by hand.
#include <gtest/gtest.h>

#include <random>
#include <vector>

#include "ffcube/formfactor/checks.hpp"
#include "support/scenes.hpp"

namespace ffcube {
namespace {

// Three patches of areas 1, 1 and 4 (unit squares and a 2 × 2 square), rows set by hand.
TEST(Checks, ReciprocityFindsTheWorstPairIncludingOneSidedEntries) {
    const Scene s = test::make_scene({test::square_z("a", 0, true), test::square_z("b", 1, false, 1.0, Vec3(0, 0, 0)),
                                      test::square_z("c", 3, false, 2.0)},
                                     10.0);
    ASSERT_EQ(s.size(), 3u);
    ASSERT_DOUBLE_EQ(s.patches[2].area, 4.0);
    CsrMatrix F(3);
    // Row 0: F_01 = 0.5, F_02 = 0.25.  Row 1: F_10 = 0.4 (off by 0.1), nothing to 2.
    // Row 2: F_20 = 0.0625 (4 × 0.0625 = 0.25: exact), F_21 = 0.05 (row 1 has no F_12).
    F.append_row(SparseRow{{1, 2}, {0.5, 0.25}});
    F.append_row(SparseRow{{0}, {0.4}});
    F.append_row(SparseRow{{0, 1}, {0.0625, 0.05}});
    const ReciprocityStats r = reciprocity_stats(F, s);
    // Pairs: (0,1): |0.5 − 0.4| / 1 = 0.1; (0,2): 0; (1,2): |0 − 4 × 0.05| / 2.5 = 0.08.
    EXPECT_NEAR(r.patch_max_abs, 0.1, 1e-7);
    // Without the (0,1) error the one-sided (1,2) pair is the worst.
    CsrMatrix G(3);
    G.append_row(SparseRow{{1, 2}, {0.5, 0.25}});
    G.append_row(SparseRow{{0}, {0.5}});
    G.append_row(SparseRow{{0, 1}, {0.0625, 0.05}});
    EXPECT_NEAR(reciprocity_stats(G, s).patch_max_abs, 0.08, 1e-7);
}

double streamed_max(const CsrMatrix& F, std::span<const double> areas, std::uint64_t max_entries, bool& complete) {
    StreamedPatchReciprocity r(areas, max_entries);
    for (std::uint32_t i = 0; i < F.size(); ++i) r.add(i, F.row(i));
    complete = r.complete();
    return r.max_abs();
}

std::vector<double> areas_of(const Scene& s) {
    std::vector<double> a;
    for (const Patch& p : s.patches) a.push_back(p.area);
    return a;
}

// The streamed check (each pair from its higher row, while the rows come) against the matrix in
// memory: the same number, bit for bit, on the hand-made rows above and on random rows with
// one-sided entries, diagonal entries and empty rows.
TEST(Checks, StreamedReciprocityIsTheMatrixOnesBitForBit) {
    {
        const Scene s = test::make_scene({test::square_z("a", 0, true), test::square_z("b", 1, false, 1.0, Vec3(0, 0, 0)),
                                          test::square_z("c", 3, false, 2.0)},
                                         10.0);
        CsrMatrix F(3);
        F.append_row(SparseRow{{1, 2}, {0.5, 0.25}});
        F.append_row(SparseRow{{0}, {0.4}});
        F.append_row(SparseRow{{0, 1}, {0.0625, 0.05}});
        bool complete = false;
        EXPECT_EQ(streamed_max(F, areas_of(s), 1000, complete), reciprocity_stats(F, s).patch_max_abs);
        EXPECT_TRUE(complete);
    }
    // 2 squares meshed to 12 × 12 and 8 × 8 cells of different areas: 208 patches.
    const Scene s = test::make_scene({test::square_z("a", 0, true, 1.0), test::square_z("b", 2, false, 1.5)}, 1.0 / 8.0);
    const std::vector<double> areas = areas_of(s);
    const auto n = static_cast<std::uint32_t>(s.size());
    ASSERT_GT(n, 150u);
    std::mt19937 rng(3);
    std::uniform_real_distribution<float> val(0.0f, 0.02f);
    for (const double density : {0.0, 0.02, 0.3, 1.0}) {
        std::bernoulli_distribution has(density);
        CsrMatrix F(n);
        for (std::uint32_t i = 0; i < n; ++i) {
            SparseRow r;
            for (std::uint32_t j = 0; j < n; ++j)
                if (has(rng)) {
                    r.col.push_back(j);
                    r.val.push_back(val(rng));
                }
            F.append_row(r);
        }
        bool complete = false;
        // A budget that holds the whole lower triangle (4 bytes a pair, within 16 a listed
        // entry): the dense triangle.
        const double got = streamed_max(F, areas, std::uint64_t{1} << 30, complete);
        EXPECT_TRUE(complete) << density;
        EXPECT_EQ(got, reciprocity_stats(F, s).patch_max_abs) << "density " << density;
        if (density > 0) {
            EXPECT_GT(got, 0.0);
        }
        // One entry short of it (5,381): the lists, which hold the entries waiting for their
        // column's row (about n²/4 × density at the middle row: 3,245 at 30%) and give up on the
        // full matrix (10,816).
        const std::uint64_t lists = static_cast<std::uint64_t>(n) * (n - 1) / 2 * 4 / 16 - 1;
        const double listed = streamed_max(F, areas, lists, complete);
        EXPECT_EQ(complete, density < 0.5) << density;
        if (complete) {
            EXPECT_EQ(listed, got) << "density " << density;
        }
    }
}

// It gives up, and says so, when the rows come out of order, when one is missing, or when the
// entries waiting for their column's row pass its budget.
TEST(Checks, StreamedReciprocityGivesUpOutOfOrderOrOverBudget) {
    const Scene s = test::make_scene({test::square_z("a", 0, true, 1.0)}, 0.25);  // 16 patches
    const std::vector<double> areas = areas_of(s);
    const auto n = static_cast<std::uint32_t>(s.size());
    CsrMatrix F(n);
    for (std::uint32_t i = 0; i < n; ++i) {
        SparseRow r;
        for (std::uint32_t j = 0; j < n; ++j)
            if (j != i) {
                r.col.push_back(j);
                r.val.push_back(0.01f * static_cast<float>(1 + (i + 2 * j) % 5));
            }
        F.append_row(r);
    }
    bool complete = false;
    streamed_max(F, areas, n * n, complete);
    EXPECT_TRUE(complete);
    // Half the matrix waits at the middle row: a budget of a tenth of it is passed.
    streamed_max(F, areas, n * n / 10, complete);
    EXPECT_FALSE(complete);
    StreamedPatchReciprocity swapped(areas, n * n);
    swapped.add(1, F.row(1));
    swapped.add(0, F.row(0));
    EXPECT_FALSE(swapped.complete());
    StreamedPatchReciprocity short_of_one(areas, n * n);
    for (std::uint32_t i = 0; i + 1 < n; ++i) short_of_one.add(i, F.row(i));
    EXPECT_FALSE(short_of_one.complete());
}

}  // namespace
}  // namespace ffcube
