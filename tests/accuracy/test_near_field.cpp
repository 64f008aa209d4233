// The near-field correction against exact object-to-object values. The inner provider here is
// the midpoint rule itself (F_ij = Lambert's point-to-polygon factor from i's centroid, no
// occlusion): what a hemicube measures in the limit of infinite resolution, so the tests are
// deterministic and need no GL. The real hemicube is measured with `ffcube bench`.
#include <gtest/gtest.h>

#include <glm/geometric.hpp>

#include <cmath>

#include "ffcube/accuracy/near_field.hpp"
#include "ffcube/core/error.hpp"
#include "ffcube/formfactor/checks.hpp"
#include "ffcube/geometry/analytic.hpp"
#include "support/scenes.hpp"

namespace ffcube {
namespace {

std::vector<Vec3> patch_polygon(const Scene& s, std::uint32_t j) {
    const auto v = s.patch_vertices(j);
    return {v.begin(), v.begin() + s.patches[j].count};
}

// Midpoint-rule rows, unoccluded (a test scene without blockers between facing patches).
CsrMatrix midpoint_matrix(const Scene& s) {
    CsrMatrix F(static_cast<std::uint32_t>(s.size()));
    for (std::uint32_t i = 0; i < s.size(); ++i) {
        SparseRow row;
        for (std::uint32_t j = 0; j < s.size(); ++j) {
            if (j == i) continue;
            // Only j's front counts (as in the hemicube): the centroid must be in front of j.
            if (glm::dot(s.patches[j].normal, s.patches[i].centroid - s.patches[j].centroid) <= 0) continue;
            const auto poly = patch_polygon(s, j);
            const double f = ff_point_polygon(s.patches[i].centroid, s.patches[i].normal, poly);
            if (f > 0) {
                row.col.push_back(j);
                row.val.push_back(f);
            }
        }
        F.append_row(row);
    }
    return F;
}

// Unit squares sharing the edge x ∈ [0,1], y = z = 0 at 90°: "a" the floor (normal +z), "b" the
// wall y = 0 (normal +y). Exact F_ab = 0.2000438 (Howell C-14).
std::vector<NamedPolygon> perpendicular_squares() {
    return {{"a", {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}}}, {"b", {{0, 0, 0}, {0, 0, 1}, {1, 0, 1}, {1, 0, 0}}}};
}

TEST(NearField, PerpendicularSquaresReachExactObjectFactor) {
    const Scene s = test::make_scene(perpendicular_squares(), 0.25);  // 4 × 4 per square
    ASSERT_EQ(s.size(), 32u);
    const double exact = ff_perpendicular_rectangles_common_edge(1, 1, 1);
    const CsrMatrix plain = midpoint_matrix(s);
    const double g_plain = object_form_factors(plain, s)[0][1];
    // The midpoint rule alone: −4.8e-4 (the pairs at d < h are −2.5e-3, the rest +2.0e-3).
    EXPECT_GT(std::abs(g_plain - exact), 4e-4);

    // Near pairs only (k = 3): those entries become exact, but the far pairs (3h ≤ d < 6h) keep
    // the midpoint rule's error, +4.5e-4 summed (computed by summing A_i (M_ij − F_ij) over
    // them), which is all one sign: the object value is no better than before. Near exactness
    // alone does not reach the target.
    MatrixRowProvider inner_near(plain);
    CorrectedRowProvider near_only(s, inner_near, NearFieldOptions{3.0, false});
    const double g_near = object_form_factors(compute_all_rows(near_only), s)[0][1];
    EXPECT_NEAR(g_near - exact, 4.5e-4, 0.1e-4);

    // Near pairs exact and sender quadrature on the rest: the far pairs' error becomes the
    // 2 × 2 Gauss rule's, O((h/d)⁴): −4.7e-7 summed (computed the same way). The assertion
    // leaves room for float storage (6e-8 relative of 0.2: 1.2e-8): 1e-5 is 20× the residual.
    MatrixRowProvider inner(plain);
    CorrectedRowProvider corrected(s, inner, NearFieldOptions{3.0, true});
    const CsrMatrix F = compute_all_rows(corrected);
    const double g = object_form_factors(F, s)[0][1];
    EXPECT_NEAR(g, exact, 1e-5);
    EXPECT_NEAR(g, exact, 1e-6);
    const NearFieldStats& st = corrected.stats();
    EXPECT_EQ(st.rows, 32u);
    EXPECT_EQ(st.refused, 0u);  // nothing else in the scene
    EXPECT_GT(st.replaced, 0u);
    EXPECT_GT(st.quadrature, 0u);
    EXPECT_EQ(st.replaced, st.near_pairs);
    // Coplanar neighbours are not facing: the pairs examined are all floor–wall pairs.
    for (std::uint32_t i = 0; i < s.size(); ++i)
        for (std::uint32_t j : F.row(i).col) EXPECT_NE(s.patches[i].object, s.patches[j].object);
}

TEST(NearField, CorrectedEntriesAreExactAndFarEntriesUnchanged) {
    const Scene s = test::make_scene(perpendicular_squares(), 0.25);
    const CsrMatrix plain = midpoint_matrix(s);
    MatrixRowProvider inner(plain);
    CorrectedRowProvider corrected(s, inner);
    const CsrMatrix F = compute_all_rows(corrected);
    for (std::uint32_t i = 0; i < s.size(); ++i)
        for (std::uint32_t j = 0; j < s.size(); ++j) {
            const double d = glm::length(s.patches[i].centroid - s.patches[j].centroid);
            if (d < 3 * 0.25 && s.patches[i].object != s.patches[j].object) {
                // Float storage: 6e-8 relative.
                const double e = ff_polygon_polygon(patch_polygon(s, i), patch_polygon(s, j));
                EXPECT_NEAR(F.at(i, j), e, 1e-7 * e) << i << " " << j;
            } else {
                EXPECT_EQ(F.at(i, j), plain.at(i, j)) << i << " " << j;
            }
        }
}

TEST(NearField, BlockerMakesThePairRefused) {
    // Two unit squares facing each other 0.5 apart (size 1 < distance 0.5·... near with k = 3),
    // and a small square blocker half-way between them: the pair cannot be proven unoccluded.
    std::vector<NamedPolygon> polys{test::square_z("low", 0, true), test::square_z("high", 0.5, false),
                                    test::square_z("blocker", 0.25, true, 0.2, Vec3(0.4, 0.4, 0))};
    const Scene s = test::make_scene(polys, 1.0);
    ASSERT_EQ(s.size(), 3u);
    const CsrMatrix plain = midpoint_matrix(s);  // ignores the blocker: any value will do here
    MatrixRowProvider inner(plain);
    CorrectedRowProvider corrected(s, inner);
    const CsrMatrix F = compute_all_rows(corrected);
    NearFieldCorrector c(s, NearFieldOptions{});
    EXPECT_FALSE(c.provably_unoccluded(0, 1));
    EXPECT_FALSE(c.provably_unoccluded(1, 0));
    // low–high refused in both rows: the values are the inner provider's.
    EXPECT_EQ(F.at(0, 1), plain.at(0, 1));
    EXPECT_EQ(F.at(1, 0), plain.at(1, 0));
    EXPECT_EQ(corrected.stats().refused, 2u);
    // The blocker's top sees the high square with nothing between: replaced by the exact value.
    EXPECT_TRUE(c.provably_unoccluded(2, 1));
    const double e = ff_polygon_polygon(patch_polygon(s, 2), patch_polygon(s, 1));
    EXPECT_NEAR(F.at(2, 1), e, 1e-7 * e);
}

TEST(NearField, BlockerOutsideTheShaftIsNoObstacle) {
    // The same blocker moved beside the pair (x ∈ [1.5, 1.7]): its bounding box misses the pair's.
    // And one leaning into the pair's box but outside the hull: x ∈ [1.05, 1.25] at height 0.25,
    // still outside the hull of the two squares (x ≤ 1 there).
    for (double x : {1.5, 1.05}) {
        std::vector<NamedPolygon> polys{test::square_z("low", 0, true), test::square_z("high", 0.5, false),
                                        test::square_z("blocker", 0.25, true, 0.2, Vec3(x, 0.4, 0))};
        const Scene s = test::make_scene(polys, 1.0);
        NearFieldCorrector c(s, NearFieldOptions{});
        EXPECT_TRUE(c.provably_unoccluded(0, 1)) << x;
    }
}

TEST(NearField, TouchingNeighboursInTheBoxCornerDoNotBlock) {
    // Inward unit box meshed 4 × 4: pairs across an edge of the box are touched by the patches of
    // the third wall at the corner and by their coplanar neighbours, which block nothing; every
    // near facing pair must be proven unoccluded (there is nothing inside the box).
    const Scene s = test::make_scene(test::inward_box(1, 1, 1), 0.25);
    CsrMatrix empty(static_cast<std::uint32_t>(s.size()));
    for (std::uint32_t i = 0; i < s.size(); ++i) empty.append_row(SparseRow{});
    MatrixRowProvider inner(empty);
    CorrectedRowProvider corrected(s, inner);
    const CsrMatrix F = compute_all_rows(corrected);
    EXPECT_EQ(corrected.stats().refused, 0u);
    EXPECT_GT(corrected.stats().replaced, 0u);
    EXPECT_EQ(corrected.stats().rows_touched, s.size());
}

TEST(NearField, RejectsBadOptions) {
    const Scene s = test::make_scene(perpendicular_squares(), 0.5);
    EXPECT_THROW(NearFieldCorrector(s, NearFieldOptions{0.0}), InputError);
    CsrMatrix small(1);
    small.append_row(SparseRow{});
    MatrixRowProvider inner(small);
    EXPECT_THROW(CorrectedRowProvider(s, inner), InputError);
}

}  // namespace
}  // namespace ffcube

namespace ffcube {
namespace {

TEST(NearField, VertexAnUlpBehindTheOtherPlaneDoesNotHang) {
    // A wall patch and a ceiling patch of a box meshed 12 × 12, as the mesher rounds them: the
    // ceiling's vertices are an ulp or two below z = 1, so the wall's top edge is 1e-16 behind
    // the ceiling's plane. ff_polygon_polygon on these exact coordinates recursed 2^50 times;
    // the corrector lifts such vertices 1e-9 of the size in front (changing F by O(1e-9)).
    std::vector<NamedPolygon> polys{
        {"wall", {{0, 0.58333333333333337, 0.91666666666666663}, {0, 0.66666666666666663, 0.91666666666666663},
                  {0, 0.66666666666666663, 1}, {0, 0.58333333333333337, 1}}},
        {"ceiling", {{0.083333333333333329, 0.41666666666666663, 0.99999999999999978},
                     {0.083333333333333329, 0.5, 0.99999999999999989}, {0.16666666666666666, 0.5, 1},
                     {0.16666666666666666, 0.41666666666666674, 0.99999999999999989}}}};
    const Scene s = test::make_scene(polys, 1.0);
    ASSERT_EQ(s.size(), 2u);
    NearFieldCorrector c(s, NearFieldOptions{});
    SparseRow row;
    NearFieldStats st;
    c.correct(0, row, st);
    ASSERT_EQ(st.replaced, 1u);
    ASSERT_EQ(row.nnz(), 1u);
    // Reference: the same pair with the ceiling exactly at z = 1. The lift moves the wall's top
    // edge by 1e-9 of the size, which changed F by 1.0e-9 relative (measured): 1e-8 leaves 10×.
    const std::vector<Vec3> wall = polys[0].vertices;
    const std::vector<Vec3> ceiling{{0.083333333333333329, 0.41666666666666663, 1},
                                    {0.083333333333333329, 0.5, 1},
                                    {0.16666666666666666, 0.5, 1},
                                    {0.16666666666666666, 0.41666666666666674, 1}};
    const double ref = ff_polygon_polygon(wall, ceiling);
    EXPECT_NEAR(row.val[0], ref, 1e-8 * ref);
    EXPECT_GT(ref, 0.0);
}

}  // namespace
}  // namespace ffcube
