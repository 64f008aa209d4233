// Matrix checks: the reciprocity figure against values worked out by hand.
#include <gtest/gtest.h>

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

}  // namespace
}  // namespace ffcube
