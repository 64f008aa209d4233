// Reciprocity and closure enforcement on closed and open scenes.
#include <gtest/gtest.h>

#include <cmath>
#include <glm/geometric.hpp>

#include "ffcube/accuracy/enforce.hpp"
#include "ffcube/core/error.hpp"
#include "ffcube/geometry/analytic.hpp"
#include "support/scenes.hpp"

namespace ffcube {
namespace {

std::vector<Vec3> patch_polygon(const Scene& s, std::uint32_t j) {
    const auto v = s.patch_vertices(j);
    return {v.begin(), v.begin() + s.patches[j].count};
}

// Exact patch-to-patch matrix (no occluders in these scenes), each entry times a deterministic
// factor in [1 − wobble, 1 + wobble] so that rows miss 1 and reciprocity fails, as a hemicube's do.
CsrMatrix wobbly_exact_matrix(const Scene& s, double wobble) {
    CsrMatrix F(static_cast<std::uint32_t>(s.size()));
    for (std::uint32_t i = 0; i < s.size(); ++i) {
        SparseRow row;
        for (std::uint32_t j = 0; j < s.size(); ++j) {
            if (j == i) continue;
            const double f = ff_polygon_polygon(patch_polygon(s, i), patch_polygon(s, j));
            if (f <= 0) continue;
            row.col.push_back(j);
            row.val.push_back(f * (1 + wobble * std::sin(1.7 * i + 2.3 * j + 0.5)));
        }
        F.append_row(row);
    }
    return F;
}

std::vector<double> areas_of(const Scene& s) {
    std::vector<double> a;
    for (const Patch& p : s.patches) a.push_back(p.area);
    return a;
}

TEST(Enforce, ClosureMakesBoxRowsSumToOneAndReciprocal) {
    const Scene s = test::make_scene(test::inward_box(1, 1, 1), 0.5);  // 24 patches
    const CsrMatrix F = wobbly_exact_matrix(s, 0.05);
    const auto areas = areas_of(s);
    EnforceStats st;
    const EnforcedMatrix E = enforce(F, areas, EnforceMode::Closure, st);
    EXPECT_GT(st.before.row_sum_max - st.before.row_sum_min, 1e-3);  // the wobble shows
    EXPECT_GT(st.before.reciprocity_max, 1e-3);
    for (std::uint32_t i = 0; i < E.n; ++i) {
        EXPECT_NEAR(E.row_sum(i), 1.0, 1e-12) << i;  // the iteration's stopping rule
        for (std::uint64_t k = E.row_ptr[i]; k < E.row_ptr[i + 1]; ++k) {
            EXPECT_GT(E.val[k], 0.0);
            const std::uint32_t j = E.col[k];
            // A_i F_ij = d_i G_ij d_j exactly symmetric up to rounding (a few ulps of 0.05).
            EXPECT_NEAR(areas[i] * E.val[k], areas[j] * E.at(j, i), 1e-12);
        }
    }
    EXPECT_LE(std::abs(st.after.row_sum_min - 1), 1e-12);
    EXPECT_LE(std::abs(st.after.row_sum_max - 1), 1e-12);
    EXPECT_LE(st.after.reciprocity_max, 1e-12);
    EXPECT_GT(st.iterations, 0u);
}

TEST(Enforce, ClosureLeavesAnExactMatrixAlone) {
    // The exact matrix of a closed box already sums to 1 and is reciprocal: enforcement may only
    // undo its float storage (6e-8 relative) and the contour integral's 1e-12.
    const Scene s = test::make_scene(test::inward_box(1, 2, 3), 1.0);
    const CsrMatrix F = wobbly_exact_matrix(s, 0.0);
    EnforceStats st;
    const EnforcedMatrix E = enforce(F, areas_of(s), parse_enforce_mode("both"), st);
    for (std::uint32_t i = 0; i < E.n; ++i)
        for (std::uint64_t k = E.row_ptr[i]; k < E.row_ptr[i + 1]; ++k) {
            const double f = F.at(i, E.col[k]);
            EXPECT_NEAR(E.val[k], f, 3e-7 * f);
        }
}

TEST(Enforce, ReciprocityOnlyAveragesAndKeepsTheUnionPattern) {
    const Scene s = test::make_scene(test::inward_box(1, 1, 1), 0.5);
    // Drop entry (0, j0) from row 0 only: the union pattern brings it back at half its weight.
    const CsrMatrix full = wobbly_exact_matrix(s, 0.02);
    CsrMatrix F(full.size());
    const std::uint32_t j0 = full.row(0).col[0];
    for (std::uint32_t i = 0; i < full.size(); ++i) {
        SparseRow r;
        for (std::size_t k = 0; k < full.row(i).col.size(); ++k) {
            if (i == 0 && full.row(i).col[k] == j0) continue;
            r.col.push_back(full.row(i).col[k]);
            r.val.push_back(full.row(i).val[k]);
        }
        F.append_row(r);
    }
    const auto areas = areas_of(s);
    EnforceStats st;
    const EnforcedMatrix E = enforce(F, areas, parse_enforce_mode("reciprocity"), st);
    EXPECT_EQ(st.iterations, 0u);
    EXPECT_LE(st.after.reciprocity_max, 1e-15);
    EXPECT_NEAR(E.at(0, j0), areas[j0] * F.at(j0, 0) / 2 / areas[0], 1e-15);
    // Any other entry: the average of the two directions.
    const std::uint32_t j1 = F.row(1).col[0];
    EXPECT_NEAR(E.at(1, j1), (areas[1] * F.at(1, j1) + areas[j1] * F.at(j1, 1)) / 2 / areas[1], 1e-15);
    // The total exchange Σ A_i F_ij is preserved by averaging.
    double before = 0, after = 0;
    for (std::uint32_t i = 0; i < F.size(); ++i) {
        before += areas[i] * F.row(i).sum();
        after += areas[i] * E.row_sum(i);
    }
    EXPECT_NEAR(before, after, 1e-12);
}

TEST(Enforce, OpenSceneIsRefused) {
    // Two perpendicular squares: most of each one's view escapes (row sums about 0.2).
    std::vector<NamedPolygon> polys{{"a", {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}}},
                                    {"b", {{0, 0, 0}, {0, 0, 1}, {1, 0, 1}, {1, 0, 0}}}};
    const Scene s = test::make_scene(polys, 0.5);
    const CsrMatrix F = wobbly_exact_matrix(s, 0.0);
    EXPECT_THROW(require_closed(F, 1e-3), InputError);
    // The closed box passes (its exact rows sum to 1 up to float storage).
    const Scene box = test::make_scene(test::inward_box(1, 1, 1), 0.5);
    EXPECT_NO_THROW(require_closed(wobbly_exact_matrix(box, 0.0), 1e-6));
    EXPECT_THROW(parse_enforce_mode("sometimes"), InputError);
}

}  // namespace
}  // namespace ffcube
