// The near-field correction against exact object-to-object values. The inner provider here is
// the midpoint rule itself (F_ij = Lambert's point-to-polygon factor from i's centroid, no
// occlusion): what a hemicube measures in the limit of infinite resolution, so the tests are
// deterministic and need no GL. The real hemicube is measured with `ffcube bench`.
#include <gtest/gtest.h>

#include <glm/geometric.hpp>

#include <cmath>
#include <numbers>
#include <random>

#include "ffcube/reference/closed_forms.hpp"
#include "ffcube/accuracy/near_field.hpp"
#include "ffcube/core/error.hpp"
#include "ffcube/formfactor/checks.hpp"
#include "ffcube/geometry/analytic.hpp"
#include "ffcube/geometry/polygon.hpp"
#include "support/closed_forms.hpp"
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

// The reference: Howell's closed forms (test::rectangle_pair_ff), not the contour integral
// the corrector calls.
double perpendicular_reference(const Scene& s, std::uint32_t i, std::uint32_t j) {
    return test::rectangle_pair_ff(s, i, j);
}

TEST(NearField, CorrectedEntriesAreExactAndFarEntriesUnchanged) {
    const Scene s = test::make_scene(perpendicular_squares(), 0.25);
    // The reference itself: summed over all pairs it is the squares' C-14 value, and it is
    // reciprocal.
    double total = 0;
    for (std::uint32_t i = 0; i < s.size(); ++i)
        for (std::uint32_t j = 0; j < s.size(); ++j)
            if (s.patches[i].object == 0 && s.patches[j].object == 1) {
                total += s.patches[i].area * perpendicular_reference(s, i, j);
                EXPECT_NEAR(s.patches[i].area * perpendicular_reference(s, i, j),
                            s.patches[j].area * perpendicular_reference(s, j, i), 1e-15);
            }
    EXPECT_NEAR(total, ff_perpendicular_rectangles_common_edge(1, 1, 1), 1e-13);
    const CsrMatrix plain = midpoint_matrix(s);
    MatrixRowProvider inner(plain);
    CorrectedRowProvider corrected(s, inner);
    const CsrMatrix F = compute_all_rows(corrected);
    std::size_t near = 0;
    for (std::uint32_t i = 0; i < s.size(); ++i)
        for (std::uint32_t j = 0; j < s.size(); ++j) {
            const double d = glm::length(s.patches[i].centroid - s.patches[j].centroid);
            if (d < 3 * 0.25 && s.patches[i].object != s.patches[j].object) {
                // Float storage: 6e-8 relative.
                const double e = perpendicular_reference(s, i, j);
                EXPECT_NEAR(F.at(i, j), e, 1e-7 * e) << i << " " << j;
                // Not what the midpoint rule gives: the replacement is visible.
                EXPECT_GT(std::abs(plain.at(i, j) - e), 1e-5 * e) << i << " " << j;
                ++near;
            } else {
                EXPECT_EQ(F.at(i, j), plain.at(i, j)) << i << " " << j;
            }
        }
    EXPECT_GT(near, 30u);
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
    // The blocker's top sees the high square with nothing between: replaced by the exact value
    // (Howell C-12: the 0.2 square at (0.4, 0.4) 0.25 below the unit square).
    EXPECT_TRUE(c.provably_unoccluded(2, 1));
    const double e = ff_parallel_rectangles_offset(0.4, 0.6, 0.4, 0.6, 0, 1, 0, 1, 0.25);
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

// Closed rows stay closed: in a closed box every point sees surfaces all round, so the exact
// rows sum to 1 and so do the midpoint rule's (inner rows here). Near entries made exact and far
// ones rescaled by the quadrature ratio no longer sum to 1 (by the quadrature rule's error on the
// near pairs); the rebalancing restores it. In double (SparseRow), so to rounding: 1e-12.
TEST(NearField, ClosedRowsStayClosedAndObjectValuesStayExact) {
    const Scene s = test::make_scene(test::inward_box(1, 1, 1), 1.0 / 6);
    const CsrMatrix plain = midpoint_matrix(s);
    const double adj = ff_perpendicular_rectangles_common_edge(1, 1, 1), opp = ff_parallel_rectangles(1, 1, 1);
    double worst_object[2] = {0, 0};
    for (const bool keep : {false, true}) {
        NearFieldOptions o;
        o.sender_quadrature = true;
        o.keep_closed_rows = keep;
        NearFieldCorrector c(s, o);
        NearFieldStats st;
        CsrMatrix F(static_cast<std::uint32_t>(s.size()));
        double worst_sum = 0;
        for (std::uint32_t i = 0; i < s.size(); ++i) {
            const auto r = plain.row(i);
            SparseRow row;
            row.col.assign(r.col.begin(), r.col.end());
            row.val.assign(r.val.begin(), r.val.end());
            EXPECT_NEAR(row.sum(), 1.0, 1e-7);  // float storage of the inner rows
            c.correct(i, row, st);
            worst_sum = std::max(worst_sum, std::abs(row.sum() - 1.0));
            F.append_row(row);
        }
        const auto G = object_form_factors(F, s);
        for (std::size_t a = 0; a < 6; ++a)
            for (std::size_t b = 0; b < 6; ++b)
                if (a != b)
                    worst_object[keep] = std::max(worst_object[keep], std::abs(G[a][b] - (a / 2 == b / 2 ? opp : adj)));
        if (keep) {
            // The inner rows sum to 1 within float storage (6e-8): every row counts as closed and
            // is rebalanced to 1 up to rounding of a few hundred doubles.
            EXPECT_LT(worst_sum, 1e-12);
            EXPECT_EQ(st.rows_closed, s.size());
            EXPECT_GT(st.closed_scale_max_change, 0.0);
        } else {
            // Without it the sums are off by the quadrature error on near pairs (measured 3.1e-5
            // at 6 × 6 per wall): more than any rounding, so the test above is not vacuous.
            EXPECT_GT(worst_sum, 1e-6);
            EXPECT_EQ(st.rows_closed, 0u);
        }
    }
    // The factor only moves far entries by the (small) residual of the near ones: object values
    // keep the correction's gain over the plain midpoint rule (measured: plain 8.4e-4 off the
    // closed forms, corrected 2.9e-6, rebalanced 1.9e-6); the rebalancing must not lose it.
    const auto G0 = object_form_factors(plain, s);
    double worst_plain = 0;
    for (std::size_t a = 0; a < 6; ++a)
        for (std::size_t b = 0; b < 6; ++b)
            if (a != b) worst_plain = std::max(worst_plain, std::abs(G0[a][b] - (a / 2 == b / 2 ? opp : adj)));
    EXPECT_LT(worst_object[0], worst_plain / 30);
    EXPECT_LE(worst_object[1], worst_object[0]);
}

// A scene that needs no correction: patches 200 sizes apart (no near pair, midpoint error
// (h/d)²/24 ≈ 1e-6 relative): rows are handed on untouched, bit for bit.
TEST(NearField, RowsThatNeedNothingAreUntouched) {
    const std::vector<NamedPolygon> polys{test::square_z("low", 0, true), test::square_z("high", 100, false)};
    const Scene s = test::make_scene(polys, 0.5);
    ASSERT_EQ(s.size(), 8u);
    const CsrMatrix plain = midpoint_matrix(s);
    MatrixRowProvider inner(plain);
    NearFieldOptions o;
    o.sender_quadrature = true;
    CorrectedRowProvider corrected(s, inner, o);
    const CsrMatrix F = compute_all_rows(corrected);
    EXPECT_EQ(F.val(), plain.val());
    EXPECT_EQ(F.col(), plain.col());
    EXPECT_EQ(corrected.stats().rows_untouched, 8u);
    EXPECT_EQ(corrected.stats().rows_quadrature, 0u);
    // Moved to 10 sizes apart, every row triggers the quadrature.
    const std::vector<NamedPolygon> closer{test::square_z("low", 0, true), test::square_z("high", 5, false)};
    const Scene s2 = test::make_scene(closer, 0.5);
    const CsrMatrix plain2 = midpoint_matrix(s2);
    MatrixRowProvider inner2(plain2);
    CorrectedRowProvider corrected2(s2, inner2, o);
    compute_all_rows(corrected2);
    EXPECT_EQ(corrected2.stats().rows_quadrature, 8u);
    EXPECT_EQ(corrected2.stats().rows_untouched, 0u);
}

// Receivers covering few pixels are detected per row: with pixel_delta_ff = 1e-4 (N ≈ 113), a
// 0.5 × 0.5 patch 100 away is worth 0.25/(π·100²) ≈ 8e-6, under 4 pixels (4e-4); 5 away it is
// worth about 3e-3: none is small.
TEST(NearField, SmallReceiversAreCounted) {
    for (const auto& [z, expect_small] : {std::pair{100.0, true}, std::pair{5.0, false}}) {
        const std::vector<NamedPolygon> polys{test::square_z("low", 0, true), test::square_z("high", z, false)};
        const Scene s = test::make_scene(polys, 0.5);
        const CsrMatrix plain = midpoint_matrix(s);
        MatrixRowProvider inner(plain);
        NearFieldOptions o;
        o.sender_quadrature = true;
        o.pixel_delta_ff = 1e-4;
        CorrectedRowProvider corrected(s, inner, o);
        compute_all_rows(corrected);
        if (expect_small) {
            EXPECT_EQ(corrected.stats().small_receiver_entries, plain.nnz()) << z;
            EXPECT_EQ(corrected.stats().rows_with_small_receivers, s.size()) << z;
        } else {
            EXPECT_EQ(corrected.stats().small_receiver_entries, 0u) << z;
            EXPECT_EQ(corrected.stats().rows_with_small_receivers, 0u) << z;
        }
    }
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

// A row the inner provider ray-cast from the whole sender (HemicubeOptions::fine_rows: the rows
// planned at 4 × 4) is estimated by the rays' noise, Σ √(f/R), with no pixel noise, no 2 × 2
// residual and no small receivers counted; the same row as sub-hemicubes keeps the pixel terms.
// Two squares 100 apart: no near pair, so the row is handed on untouched with its estimate.
TEST(NearField, ARayCastRowIsEstimatedByTheRaysNoise) {
    const std::vector<NamedPolygon> polys{test::square_z("low", 0, true), test::square_z("high", 100, false)};
    const Scene s = test::make_scene(polys, 0.5);
    NearFieldOptions o;
    o.sender_quadrature = true;
    o.pixel_delta_ff = 1e-4;
    NearFieldCorrector c(s, o);
    NearFieldScratch scratch;
    const SparseRow inner{{4, 5}, {2e-6, 3e-6}};
    const double rays = 65536;
    const double expected = std::sqrt(2e-6 / rays) + std::sqrt(3e-6 / rays);
    SparseRow row = inner;
    NearFieldStats cast_stats, drawn_stats;
    double cast = 0, drawn = 0;
    c.correct(0, row, cast_stats, scratch, &cast, nullptr, true, rays);
    EXPECT_EQ(row.val, inner.val);
    EXPECT_DOUBLE_EQ(cast, expected);
    EXPECT_EQ(cast_stats.small_receiver_entries, 0u);
    row = inner;
    c.correct(0, row, drawn_stats, scratch, &drawn, nullptr, true);
    EXPECT_GT(drawn, 2 * expected);  // the pixel noise of receivers worth a few hundredths of a pixel
    EXPECT_EQ(drawn_stats.small_receiver_entries, 2u);
}

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

// Near pairs whose bounding spheres are at least 2 radii of the smaller one apart take their
// value from a 6 × 6 Gauss rule on the smaller patch (clipped to the other's front) with Lambert's
// formula, not from the contour integral (docs/accuracy.md). Random facing pairs, parallelograms
// and triangles in random orientations, sizes 0.1..10 apart, gaps of 2–3 small radii, each a
// two-patch scene (nothing can block): the value must match ff_polygon_polygon within 1e-9
// relative (the rule's worst over 3,000 such pairs was 3.6e-10), and the row's error estimate
// must cover the difference.
TEST(NearField, SeparatedNearPairsMatchTheContourIntegral) {
    std::mt19937_64 rng(2026);
    std::uniform_real_distribution<double> u(-1.0, 1.0);
    const auto random_patch = [&](double size, const Vec3& c, const Vec3& facing) {
        Vec3 n = glm::normalize(Vec3(u(rng), u(rng), u(rng)));
        if (glm::dot(n, facing) < 0.2) n = glm::normalize(n + facing);  // facing the other, not edge-on
        const Vec3 t = glm::normalize(glm::cross(n, Vec3(u(rng), u(rng), u(rng))));
        const Vec3 b = glm::cross(n, t);
        const double w = size * (0.65 + 0.35 * u(rng)), h = size * (0.65 + 0.35 * u(rng)), shear = 0.3 * size * u(rng);
        std::vector<Vec3> p = {c - 0.5 * w * t - 0.5 * h * b, c + 0.5 * w * t - 0.5 * h * b,
                               c + 0.5 * w * t + 0.5 * h * b + shear * t, c - 0.5 * w * t + 0.5 * h * b + shear * t};
        if (u(rng) > 0.5) p.pop_back();
        // Counter-clockwise seen from the front (n): t, b is right-handed about n.
        return p;
    };
    const auto radius = [](const Scene& s, std::uint32_t i) {
        double r = 0;
        const auto v = s.patch_vertices(i);
        for (std::uint32_t k = 0; k < s.patches[i].count; ++k) r = std::max(r, glm::length(v[k] - s.patches[i].centroid));
        return r;
    };
    int separated = 0;
    for (int trial = 0; trial < 400 && separated < 60; ++trial) {
        const double size_b = std::pow(10.0, u(rng));
        const Vec3 dir = glm::normalize(Vec3(u(rng), u(rng), u(rng)));
        const double ra = 0.75, rb = 0.75 * size_b;  // about the radii; the test measures the real ones
        const Vec3 cb = dir * (ra + rb + 2.5 * std::min(ra, rb));
        std::vector<NamedPolygon> polys = {{"a", random_patch(1.0, Vec3(0.0), dir)}, {"b", random_patch(size_b, cb, -dir)}};
        const Scene s = test::make_scene(polys, 100.0);  // one patch each
        ASSERT_EQ(s.size(), 2u);
        const double d = glm::length(s.patches[1].centroid - s.patches[0].centroid);
        const double r0 = radius(s, 0), r1 = radius(s, 1);
        const bool is_separated = d - r0 - r1 >= 2 * std::min(r0, r1);
        const bool near = d < 3.0 * std::max(s.patches[0].size, s.patches[1].size);
        if (!is_separated || !near) continue;
        NearFieldCorrector c(s, NearFieldOptions{});
        NearAnalysis a;
        c.analyse(0, a);
        const auto v0 = s.patch_vertices(0), v1 = s.patch_vertices(1);
        const double exact = ff_polygon_polygon(std::span<const Vec3>(v0.data(), s.patches[0].count),
                                                std::span<const Vec3>(v1.data(), s.patches[1].count));
        if (!(exact > 1e-12)) continue;  // facing only in part: the pair may be skipped as not facing
        ASSERT_EQ(a.exact.size(), 1u) << trial;
        EXPECT_NEAR(a.exact[0].second, exact, 1e-9 * exact) << trial;
        EXPECT_GE(a.far_error, std::abs(a.exact[0].second - exact)) << trial;
        ++separated;
    }
    EXPECT_GE(separated, 60);
}

// Asking for no rows hands nothing to the sink and does not fail (a resumed checkpoint, or an MPI
// rank's shard, that already holds every row asks for none). A row out of range is refused before
// any work; a row listed twice is measured twice, each time the same row with the same figures
// (they go with the row, RowSide: no shared per-row array is written).
TEST(NearField, NoRowsAskedIsNothingToDoAndARowListedTwiceIsMeasuredTwice) {
    const Scene s = test::make_scene(perpendicular_squares(), 0.25);
    const CsrMatrix plain = midpoint_matrix(s);
    MatrixRowProvider inner(plain);
    CorrectedRowProvider corrected(s, inner);
    std::vector<SparseRow> delivered;
    const auto keep = [&](std::uint32_t, const SparseRow& r) { delivered.push_back(r); };
    corrected.compute_rows({}, keep);
    EXPECT_TRUE(delivered.empty());
    const std::vector<std::uint32_t> out_of_range = {1, static_cast<std::uint32_t>(s.size())};
    EXPECT_THROW(corrected.compute_rows(out_of_range, keep), InternalError);
    EXPECT_TRUE(delivered.empty());
    const std::vector<std::uint32_t> twice = {0, 1, 0};
    corrected.compute_rows(twice, keep);
    ASSERT_EQ(delivered.size(), 3u);
    EXPECT_EQ(delivered[0].col, delivered[2].col);
    EXPECT_EQ(delivered[0].val, delivered[2].val);
    EXPECT_EQ(delivered[0].side, delivered[2].side);
    EXPECT_FALSE(std::isnan(delivered[0].side.error)) << "a corrected row carries its estimate";
    EXPECT_GE(delivered[0].side.measure, 0);
}

}  // namespace
}  // namespace ffcube

namespace ffcube {
namespace {

// A wall standing on a ground quad that runs on under it (a ground plane split into triangles,
// with buildings on top, as a CAD or GIS export writes a city). Only the ground in front of the
// wall exchanges radiation with it, so what stands behind the wall cannot block the pair: the
// shaft is the hull of the parts in front of each other's plane.
std::vector<NamedPolygon> wall_on_ground(const NamedPolygon& extra) {
    return {NamedPolygon{"wall", {Vec3(0, 0, 0), Vec3(0, 0, 1), Vec3(0, 1, 1), Vec3(0, 1, 0)}},  // faces −x
            NamedPolygon{"ground", {Vec3(-1, 0, 0), Vec3(1, 0, 0), Vec3(1, 1, 0), Vec3(-1, 1, 0)}},  // faces +z
            extra};
}

TEST(NearField, WhatStandsBehindTheWallDoesNotBlockItsGround) {
    // Behind the wall (x = 0.5), inside the hull of the whole wall and the whole ground.
    const Scene s = test::make_scene(
        wall_on_ground({"behind", {Vec3(0.5, 0.2, 0), Vec3(0.5, 0.2, 0.5), Vec3(0.5, 0.8, 0.5), Vec3(0.5, 0.8, 0)}}),
        10.0);
    ASSERT_EQ(s.size(), 3u);
    NearFieldCorrector c(s, NearFieldOptions{});
    EXPECT_TRUE(c.provably_unoccluded(0, 1));
    EXPECT_TRUE(c.provably_unoccluded(1, 0));
    // Its value is the front half's: unit squares sharing an edge at right angles (C-14),
    // against the exact value of the inner provider's plain rows. The near value is the contour
    // integral, 1e-9 relative (docs/accuracy.md); float storage of the matrix, 6e-8.
    const CsrMatrix plain = midpoint_matrix(s);
    MatrixRowProvider inner(plain);
    CorrectedRowProvider corrected(s, inner);
    const CsrMatrix F = compute_all_rows(corrected);
    const double e = ff_perpendicular_rectangles_common_edge(1, 1, 1);
    EXPECT_NEAR(F.at(0, 1), e, 1e-7 * e);
}

TEST(NearField, WhatStandsInFrontOfTheWallStillBlocks) {
    // A small plate above the ground in front of the wall (x ∈ [−0.6, −0.4], z = 0.3): it cuts
    // segments from the wall to the front half of the ground.
    const Scene s = test::make_scene(
        wall_on_ground({"plate", {Vec3(-0.6, 0.4, 0.3), Vec3(-0.4, 0.4, 0.3), Vec3(-0.4, 0.6, 0.3), Vec3(-0.6, 0.6, 0.3)}}),
        10.0);
    ASSERT_EQ(s.size(), 3u);
    NearFieldCorrector c(s, NearFieldOptions{});
    EXPECT_FALSE(c.provably_unoccluded(0, 1));
    EXPECT_FALSE(c.provably_unoccluded(1, 0));
}

}  // namespace
}  // namespace ffcube

namespace ffcube {
namespace {

// NearFieldOptions::min_near_value's bound, F_ij ≤ A_j / (π gap²) with gap = centroid distance
// − both bounding radii, against the contour integral over random pairs of triangles and quads
// (random sizes, orientations and places, gap > 0): it must never be below the exact value.
// Its slack where it is tight (a small receiver straight above the sender) is also checked, so a
// bound made looser by a constant would fail too.
TEST(NearField, MinNearValueBoundsTheExactFactor) {
    std::mt19937_64 rng(11);
    std::uniform_real_distribution<double> u(-1.0, 1.0);
    const auto polygon = [&](int corners, double size, const Vec3& at) {
        Vec3 a = glm::normalize(Vec3(u(rng), u(rng), u(rng)) + Vec3(1e-3, 0, 0)), b;
        b = glm::normalize(glm::cross(a, Vec3(u(rng), u(rng), u(rng)) + Vec3(0, 1e-3, 0)));
        const Vec3 c = glm::cross(a, b);
        std::vector<Vec3> p;
        for (int k = 0; k < corners; ++k) {
            const double t = 2 * std::numbers::pi * (k + 0.3 * u(rng)) / corners;
            p.push_back(at + size * (std::cos(t) * b + std::sin(t) * c));
        }
        return p;
    };
    const auto radius = [](const std::vector<Vec3>& p) {
        const Vec3 c = polygon_centroid(p);
        double r = 0;
        for (const Vec3& v : p) r = std::max(r, glm::length(v - c));
        return r;
    };
    int tried = 0;
    for (int n = 0; n < 3000; ++n) {
        const auto a = polygon(3 + n % 2, std::exp(2 * u(rng)), Vec3(0.0));
        const auto b = polygon(3 + (n / 2) % 2, std::exp(2 * u(rng)), 8.0 * Vec3(u(rng), u(rng), u(rng)));
        const double gap = glm::length(polygon_centroid(b) - polygon_centroid(a)) - radius(a) - radius(b);
        if (!(gap > 0)) continue;
        ++tried;
        const double bound = polygon_area(b) / (std::numbers::pi * gap * gap);
        EXPECT_LE(ff_polygon_polygon(a, b), bound) << n;
    }
    EXPECT_GT(tried, 500);
    // Tight: a 0.01 square 1 above a 0.01 square: F ≈ A/(π d²) = 3.18e-5; the bound uses gap =
    // 1 − 2 · 0.00707, 3% above.
    const std::vector<Vec3> lo{{0, 0, 0}, {0.01, 0, 0}, {0.01, 0.01, 0}, {0, 0.01, 0}};
    const std::vector<Vec3> hi{{0, 0, 1}, {0, 0.01, 1}, {0.01, 0.01, 1}, {0.01, 0, 1}};
    const double gap = 1 - 2 * radius(lo);
    EXPECT_NEAR(ff_polygon_polygon(lo, hi) / (1e-4 / (std::numbers::pi * gap * gap)), 1.0, 0.03);
}

// A near pair whose bound is below min_near_value keeps the inner provider's entry (no shaft
// test, no exact value) and is counted; the others become exact as before. Two unit squares
// facing each other 1.2 apart, 2 × 2 patches of 0.5 each (bounding radius 0.354): every pair is
// near (d ≤ 1.39 < 3 × 0.5), and the bounds are 0.33 for the patch straight across, 0.23 for
// the ones beside it and 0.17 diagonally, so min_near_value = 0.25 leaves 3 of each row's 4
// pairs as measured.
TEST(NearField, PairsBelowMinNearValueKeepTheirMeasuredEntry) {
    const std::vector<NamedPolygon> polys{test::square_z("low", 0, true), test::square_z("high", 1.2, false)};
    const Scene s = test::make_scene(polys, 0.5);
    ASSERT_EQ(s.size(), 8u);
    const CsrMatrix plain = midpoint_matrix(s);
    NearFieldOptions o;
    o.min_near_value = 0.25;
    MatrixRowProvider inner(plain);
    CorrectedRowProvider corrected(s, inner, o);
    const CsrMatrix F = compute_all_rows(corrected);
    int exact = 0, kept = 0;
    for (std::uint32_t i = 0; i < s.size(); ++i)
        for (std::uint32_t j = 0; j < s.size(); ++j) {
            if (s.patches[i].object == s.patches[j].object) continue;
            const double d = glm::length(s.patches[i].centroid - s.patches[j].centroid);
            if (d < 1.2 + 1e-9) {
                // Float storage: 6e-8 relative; the midpoint rule is off by more than that.
                const double e = test::rectangle_pair_ff(s, i, j);
                EXPECT_NEAR(F.at(i, j), e, 1e-7 * e) << i << " " << j;
                EXPECT_GT(std::abs(plain.at(i, j) - e), 1e-5 * e) << i << " " << j;
                ++exact;
            } else {
                EXPECT_EQ(F.at(i, j), plain.at(i, j)) << i << " " << j;
                ++kept;
            }
        }
    EXPECT_EQ(exact, 8);
    EXPECT_EQ(kept, 24);
    EXPECT_EQ(corrected.stats().below_value, 24u);
    EXPECT_EQ(corrected.stats().near_pairs, 8u);
    EXPECT_EQ(corrected.stats().replaced, 8u);
    // 0 (the struct's default): every near pair exact.
    MatrixRowProvider inner_all(plain);
    CorrectedRowProvider all(s, inner_all, NearFieldOptions{});
    compute_all_rows(all);
    EXPECT_EQ(all.stats().below_value, 0u);
    EXPECT_EQ(all.stats().replaced, 32u);
    o.min_near_value = 1.5;
    EXPECT_THROW(NearFieldCorrector(s, o), InputError);
}

}  // namespace
}  // namespace ffcube
