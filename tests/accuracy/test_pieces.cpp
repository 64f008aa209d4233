// The accuracy layer's pieces on their own (src/accuracy/*.hpp), each against a brute-force
// reference: the grid against a scan of every patch, the shaft test against segments sampled
// through the shaft, the rebalancing against its contract, the merge against a hand-made row.
#include <gtest/gtest.h>

#include <glm/geometric.hpp>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <vector>

#include "accuracy/patch_set.hpp"
#include "accuracy/rebalance.hpp"
#include "accuracy/row_error.hpp"
#include "accuracy/row_merge.hpp"
#include "accuracy/shaft_test.hpp"
#include "accuracy/spatial_grid.hpp"
#include "ffcube/geometry/quadrature.hpp"
#include "support/scenes.hpp"
#include "support/segments.hpp"

namespace ffcube {
namespace {

using accuracy::Box;
using test::Rng;

Vec3 random_unit(Rng& rng) {
    for (;;) {
        const Vec3 v(rng(-1, 1), rng(-1, 1), rng(-1, 1));
        const double l = glm::length(v);
        if (l > 0.1 && l <= 1) return v / l;
    }
}

// A planar parallelogram (or half of one: a triangle) about c with normal n, sides about `size`.
std::vector<Vec3> random_facet(Rng& rng, const Vec3& c, const Vec3& n, double size) {
    const Vec3 t = glm::normalize(glm::cross(n, random_unit(rng)));
    const Vec3 b = glm::cross(n, t);
    const Vec3 a = t * (size * rng(0.5, 1.0)), d = (b + t * rng(-0.3, 0.3)) * (size * rng(0.5, 1.0));
    std::vector<Vec3> p{c - 0.5 * a - 0.5 * d, c + 0.5 * a - 0.5 * d, c + 0.5 * a + 0.5 * d, c - 0.5 * a + 0.5 * d};
    if (rng() < 0.3) p.pop_back();
    return p;
}

// A random scene of one patch per facet: sizes over two decades, and one facet far larger than
// the rest (the grid keeps such patches on a list of their own).
Scene random_scene(std::uint64_t seed, int count) {
    Rng rng(seed);
    std::vector<NamedPolygon> polys;
    for (int k = 0; k < count; ++k) {
        const Vec3 c(rng(0, 4), rng(0, 4), rng(0, 4));
        polys.push_back({"f" + std::to_string(k), random_facet(rng, c, random_unit(rng), 0.05 * std::pow(10.0, rng(0, 2)))});
    }
    polys.push_back({"big", random_facet(rng, Vec3(2, 2, 2), Vec3(0, 0, 1), 40.0)});
    return test::make_scene(polys, 1e3);
}

std::vector<std::uint32_t> brute_query(const accuracy::PatchSet& ps, const Box& box) {
    std::vector<std::uint32_t> out;
    for (std::uint32_t q = 0; q < ps.size(); ++q)
        if (ps.boxes[q].overlaps(box)) out.push_back(q);
    return out;
}

TEST(SpatialGrid, QueriesFindExactlyTheOverlappingBoxes) {
    const Scene s = random_scene(17, 400);
    const accuracy::PatchSet ps(s);
    const accuracy::SpatialGrid grid(ps);
    EXPECT_EQ(grid.big_patches(), 1u);  // the 40-unit facet: the test covers the big list
    Rng rng(5);
    std::vector<std::uint32_t> got;
    std::size_t hits = 0;
    for (int q = 0; q < 500; ++q) {
        const Vec3 c(rng(-1, 5), rng(-1, 5), rng(-1, 5));
        // From far below the cell size to boxes spanning more than kMaxCellsPerQuery cells.
        const Vec3 half = Vec3(rng(), rng(), rng()) * std::pow(10.0, rng(-3, 0.7));
        const Box box{c - half, c + half};
        grid.query(box, got);
        const auto want = brute_query(ps, box);
        ASSERT_EQ(got, want) << q;
        hits += want.size();
    }
    EXPECT_GT(hits, 2000u);  // the queries do find patches
}

// visit (the shaft test's search) calls back exactly the overlapping patches, each once, and
// stops at the first false.
TEST(SpatialGrid, VisitCallsEachOverlappingBoxOnceAndStopsWhenAsked) {
    const Scene s = random_scene(17, 400);
    const accuracy::PatchSet ps(s);
    const accuracy::SpatialGrid grid(ps);
    Rng rng(6);
    std::size_t stopped = 0;
    for (int q = 0; q < 500; ++q) {
        const Vec3 c(rng(-1, 5), rng(-1, 5), rng(-1, 5));
        const Vec3 half = Vec3(rng(), rng(), rng()) * std::pow(10.0, rng(-3, 0.7));
        const Box box{c - half, c + half};
        std::vector<std::uint32_t> got;
        EXPECT_TRUE(grid.visit(box, [&](std::uint32_t p) { got.push_back(p); return true; }));
        std::sort(got.begin(), got.end());
        ASSERT_EQ(got, brute_query(ps, box)) << q;  // sorted and equal: each exactly once
        if (got.size() < 2) continue;
        std::size_t calls = 0;
        EXPECT_FALSE(grid.visit(box, [&](std::uint32_t) { return ++calls < 2; }));
        EXPECT_EQ(calls, 2u);
        ++stopped;
    }
    EXPECT_GT(stopped, 100u);
}

// The near pairs as the corrector finds them (query a box of k × the largest size about the
// centroid, then the distance test) are exactly the pairs within k × max(size_i, size_j).
TEST(SpatialGrid, FindsExactlyTheNearPairs) {
    const Scene s = random_scene(23, 300);
    const accuracy::PatchSet ps(s);
    const accuracy::SpatialGrid grid(ps);
    const double k = 3.0;
    std::vector<std::uint32_t> cand;
    std::size_t pairs = 0;
    for (std::uint32_t i = 0; i < s.size(); ++i) {
        const Patch& pi = s.patches[i];
        const double reach = k * std::max(pi.size, ps.max_size);
        grid.query(Box{pi.centroid - Vec3(reach), pi.centroid + Vec3(reach)}, cand);
        std::vector<std::uint32_t> got, want;
        for (std::uint32_t j : cand)
            if (j != i && glm::length(s.patches[j].centroid - pi.centroid) < k * std::max(pi.size, s.patches[j].size))
                got.push_back(j);
        for (std::uint32_t j = 0; j < s.size(); ++j)
            if (j != i && glm::length(s.patches[j].centroid - pi.centroid) < k * std::max(pi.size, s.patches[j].size))
                want.push_back(j);
        ASSERT_EQ(got, want) << i;
        pairs += want.size();
    }
    EXPECT_GT(pairs, 300u);
}

// Random configurations: two facing facets and three blockers placed about the segment between
// them. Brute force: 256 random segments and the 16 corner-to-corner ones, each against every
// blocker (test::crosses_interior, independent of the code under test). The shaft test must
// never accept a configuration where a segment is blocked, and must accept most of those where
// none is and the blockers lie outside the pair's hull in the first place.
// Two facets a and b facing each other about a random direction, and three blockers q0..q2 at
// random points of the segment between their centres, moved off it by up to `spread`; `across`:
// the blockers face along the segment (so they lie across it), else any way.
std::vector<NamedPolygon> shaft_configuration(Rng& rng, double spread, bool across) {
    const Vec3 ca(0.0), dir = random_unit(rng);
    const double dist = rng(0.8, 3.0);
    const Vec3 cb = ca + dir * dist;
    std::vector<NamedPolygon> polys{{"a", random_facet(rng, ca, glm::normalize(dir + 0.6 * random_unit(rng)), 1.0)},
                                    {"b", random_facet(rng, cb, glm::normalize(-dir + 0.6 * random_unit(rng)), 1.0)}};
    for (int q = 0; q < 3; ++q) {
        const Vec3 c = ca + dir * (dist * rng(0.1, 0.9)) + random_unit(rng) * rng(0.0, spread);
        const Vec3 n = across ? glm::normalize(dir + 0.3 * random_unit(rng)) : random_unit(rng);
        polys.push_back({"q" + std::to_string(q), random_facet(rng, c, n, rng(0.1, 0.8))});
    }
    return polys;
}

TEST(ShaftTest, NeverAcceptsABlockedShaft) {
    Rng rng(99);
    std::size_t blocked = 0, free = 0, free_accepted = 0;
    for (int trial = 0; trial < 600; ++trial) {
        const Scene s = test::make_scene(shaft_configuration(rng, 1.5, false), 1e3);
        ASSERT_EQ(s.size(), 5u);
        const accuracy::PatchSet ps(s);
        if (!ps.facing(0, 1)) continue;
        const accuracy::SpatialGrid grid(ps);
        accuracy::ShaftScratch scratch;
        const bool accepted = accuracy::shaft_unoccluded(ps, grid, 0, 1, scratch);
        const double eps = 1e-9 * s.extent();
        std::vector<test::TestPoly> blockers;
        for (std::uint32_t q = 2; q < 5; ++q) blockers.push_back(test::test_poly(s, q));
        const auto va = test::patch_vertex_list(s, 0), vb = test::patch_vertex_list(s, 1);
        bool hit = false;
        const auto check = [&](const Vec3& x, const Vec3& y) {
            for (const auto& q : blockers) hit = hit || test::crosses_interior(x, y, q, eps);
        };
        for (int k = 0; k < 256 && !hit; ++k) check(test::random_point(s, 0, rng), test::random_point(s, 1, rng));
        for (const Vec3& x : va)
            for (const Vec3& y : vb) check(x, y);
        if (hit) {
            ++blocked;
            EXPECT_FALSE(accepted) << "trial " << trial << ": a blocked shaft was accepted";
        } else {
            ++free;
            free_accepted += accepted;
        }
    }
    // Both kinds occur often enough for the test to mean something.
    EXPECT_GE(blocked, 50u);
    EXPECT_GE(free, 50u);
    // Conservative, not vacuous: most shafts the sampling finds free are proven free.
    RecordProperty("free_accepted_percent", std::to_string(100.0 * static_cast<double>(free_accepted) / static_cast<double>(free)));
    EXPECT_GE(free_accepted * 10, free * 5) << free_accepted << " of " << free;
}

// The last blocker found is tried first by the next call (ShaftScratch::last_blocker), and
// answers it before any axis is made when it crosses the segment between the two parts' centres
// deep inside (crosses_deep). Neither may change an answer: on configurations like those above
// (every other trial with the blockers crowded within 0.3 of the segment, every fourth with them
// facing along it, so across it), the answer with each of the three blockers as the hint equals
// the answer with none; and the deep crossing must have answered some calls (546 here).
TEST(ShaftTest, TheBlockerTriedFirstNeverChangesTheAnswer) {
    Rng rng(5);
    std::size_t compared = 0, refused = 0;
    std::uint64_t deep = 0;
    for (int trial = 0; trial < 800; ++trial) {
        const Scene s = test::make_scene(shaft_configuration(rng, trial % 2 ? 0.3 : 1.5, trial % 4 == 0), 1e3);
        ASSERT_EQ(s.size(), 5u);
        const accuracy::PatchSet ps(s);
        if (!ps.facing(0, 1)) continue;
        const accuracy::SpatialGrid grid(ps);
        accuracy::ShaftScratch fresh;
        const bool want = accuracy::shaft_unoccluded(ps, grid, 0, 1, fresh);
        refused += !want;
        for (std::uint32_t hint = 2; hint < 5; ++hint) {
            accuracy::ShaftScratch scratch;
            scratch.last_blocker = hint;
            ASSERT_EQ(accuracy::shaft_unoccluded(ps, grid, 0, 1, scratch), want) << "trial " << trial << " hint " << hint;
            deep += scratch.deep_crossings;
            ++compared;
        }
    }
    EXPECT_GT(compared, 1000u);
    EXPECT_GT(refused, 100u);
    EXPECT_GT(deep, 50u) << "the deep crossing never answered: this compares only the ordering";
}

// Rebalancing: a closed row sums to 1 afterwards, no row it changes exceeds 1, exact entries
// keep their value whenever the others can absorb the change, and a change beyond 10% is
// refused (the row is left as it was).
TEST(Rebalance, ClosedRowsSumToOneAndNoRowExceedsOne) {
    Rng rng(7);
    std::size_t applied_closed = 0, applied_capped = 0, refused = 0, rest_only = 0;
    for (int trial = 0; trial < 2000; ++trial) {
        const auto n = static_cast<std::size_t>(rng(1, 40));
        std::vector<double> v(n);
        std::vector<std::uint8_t> exact(n);
        for (std::size_t e = 0; e < n; ++e) {
            v[e] = rng(0.0, 1.0);
            exact[e] = rng() < rng();  // rows from all-exact to none exact
        }
        const double target = rng(0.85, 1.15);  // the row's sum before rebalancing
        double sum = 0;
        for (double x : v) sum += x;
        for (double& x : v) x *= target / sum;
        const std::vector<double> before = v;
        accuracy::ClosedTest test;
        test.inner_sum = rng() < 0.5 ? 1.0 + rng(-5e-8, 5e-8) : rng(0.5, 0.99);  // closed or open
        const accuracy::Rebalance r = accuracy::rebalance_row(v, exact, test);
        EXPECT_EQ(r.closed, std::abs(test.inner_sum - 1.0) <= accuracy::kClosedRowTolerance);
        double after = 0, moved = 0;
        bool exact_kept = true;
        for (std::size_t e = 0; e < n; ++e) {
            after += v[e];
            moved += std::abs(v[e] - before[e]);
            if (exact[e]) exact_kept = exact_kept && v[e] == before[e];
        }
        if (!r.applied) {
            EXPECT_EQ(v, before);
            // Left alone: an open row at most 1, or a change the factor would amplify beyond 10%.
            if (!r.closed && target <= 1.0) continue;
            ++refused;
            EXPECT_GT(std::abs(1.0 / target - 1.0), 0.1 - 1e-12) << trial;
            continue;
        }
        EXPECT_TRUE(r.closed || target > 1.0);
        ++(r.closed ? applied_closed : applied_capped);
        EXPECT_NEAR(after, 1.0, 1e-12) << trial;  // closed rows sum to 1; capped rows come down to 1
        EXPECT_LE(r.factor, r.closed ? 1.1 : 1.0);
        EXPECT_NEAR(r.moved, moved, 1e-12) << trial;  // the estimate's term is what was moved
        if (exact_kept && std::any_of(exact.begin(), exact.end(), [](auto x) { return x != 0; })) ++rest_only;
    }
    EXPECT_GT(applied_closed, 200u);
    EXPECT_GT(applied_capped, 100u);
    EXPECT_GT(refused, 50u);
    EXPECT_GT(rest_only, 100u);
}

// An analytic row (not measured) counts as closed when its own sum is 1 within twice its
// values' error bounds.
TEST(Rebalance, AnalyticRowsAreClosedWithinTheirErrorBound) {
    std::vector<double> v{0.5, 0.5 - 3e-6};
    const std::vector<std::uint8_t> exact{1, 1};
    accuracy::ClosedTest t;
    t.analytic = true;
    t.analytic_error = 1e-6;  // 2e-6 < 3e-6: open, and below 1: left alone
    EXPECT_FALSE(accuracy::rebalance_row(v, exact, t).closed);
    t.analytic_error = 2e-6;
    const auto r = accuracy::rebalance_row(v, exact, t);
    EXPECT_TRUE(r.closed);
    EXPECT_TRUE(r.applied);
    EXPECT_NEAR(v[0] + v[1], 1.0, 1e-15);
}

// The merge: exact columns take their value (an exact 0 drops the entry, even where the inner
// row had one), the others keep theirs (no quadrature here), columns stay increasing.
TEST(RowMerge, ExactColumnsReplaceAndZerosDrop) {
    const Scene s = test::make_scene({test::square_z("low", 0, true), test::square_z("high", 1, false)}, 0.5);
    ASSERT_EQ(s.size(), 8u);
    const accuracy::PatchSet ps(s);
    SparseRow inner;
    inner.col = {1, 4, 5, 7};
    inner.val = {0.1, 0.2, 0.3, 0.4};
    const std::vector<std::pair<std::uint32_t, double>> exact{{2, 0.05}, {4, 0.25}, {5, 0.0}, {6, 0.125}};
    const accuracy::RowErrorModel error{s, s.patches[0], 0, 0, false, false};
    std::vector<Vec3> qp;
    std::vector<double> qw;
    const NearFieldOptions options;
    const accuracy::SenderQuadrature rule(ps, options, 0, error, false, qp, qw);
    accuracy::MergedRow out;
    double estimate = 0;
    EXPECT_EQ(accuracy::merge_row(inner, exact, rule, error, out, estimate), 0u);
    EXPECT_EQ(out.row.col, (std::vector<std::uint32_t>{1, 2, 4, 6, 7}));
    EXPECT_EQ(out.row.val, (std::vector<double>{0.1, 0.05, 0.25, 0.125, 0.4}));
    EXPECT_EQ(out.is_exact, (std::vector<std::uint8_t>{0, 1, 1, 1, 0}));
    EXPECT_EQ(estimate, 0.0);  // no quadrature, no noise model: the kept entries add nothing
}

// A row's noise terms two at a time (SSE2) are the scalar ones, bit for bit: values over twelve
// decades, odd and even lengths, each model (pixels, rays, both).
TEST(RowError, NoiseOfARowIsTheScalarsBitForBit) {
    const Scene s = test::make_scene({test::square_z("low", 0, true), test::square_z("high", 1, false)}, 0.5);
    Rng rng(11);
    for (const auto& [dF, rays] : {std::pair{1e-5, 0.0}, std::pair{0.0, 4096.0}, std::pair{3e-6, 100.0}}) {
        const accuracy::RowErrorModel error{s, s.patches[0], dF, rays, false, true};
        for (std::size_t n : {0u, 1u, 2u, 7u, 64u}) {
            std::vector<double> f(n), out(n, -1.0);
            for (double& v : f) v = std::pow(10.0, rng(-12, 0));
            error.noise(f, out.data());
            for (std::size_t a = 0; a < n; ++a) EXPECT_EQ(out[a], error.noise(f[a])) << "dF " << dF << " rays " << rays;
        }
    }
}

// The sender quadrature's far entries (6 to 64 sizes: the point kernel), computed two points at a
// time, are the scalar statement of the rule bit for bit: the ratio of the 2 × 2 rule's kernel
// sum to the centroid's, applied when within 25% of 1. Random facets (quads and triangles, sizes
// over two decades, arbitrary orientations: kernels that vanish behind either plane included).
TEST(SenderQuadrature, PointKernelRatiosAreTheScalarRuleBitForBit) {
    const Scene s = random_scene(5, 300);
    const accuracy::PatchSet ps(s);
    const NearFieldOptions options;
    std::size_t checked = 0, applied = 0;
    std::vector<Vec3> qp, pts;
    std::vector<double> qw, wts;
    for (std::uint32_t i = 0; i < s.size(); i += 7) {
        const Patch& pi = s.patches[i];
        const accuracy::RowErrorModel error{s, pi, 1e-5, 0, false, true};
        const accuracy::SenderQuadrature rule(ps, options, i, error, true, qp, qw);
        patch_quadrature(ps.polys[i].span(), 2, pts, wts);
        for (std::uint32_t j = 0; j < s.size(); ++j) {
            const Patch& pj = s.patches[j];
            const double d = glm::length(pj.centroid - pi.centroid), size = std::max(pi.size, pj.size);
            if (j == i || d < 6.0 * size || d >= options.quadrature_k * size) continue;
            const auto kernel = [&](const Vec3& x) {
                const Vec3 r = pj.centroid - x;
                const double r2 = glm::dot(r, r);
                return std::max(0.0, glm::dot(pi.normal, r)) * std::max(0.0, -glm::dot(pj.normal, r)) / (r2 * r2);
            };
            const double f = 0.01, mid = kernel(pi.centroid);
            double expected = f;
            if (mid > 0) {
                double q = 0;
                for (std::size_t k = 0; k < pts.size(); ++k) q += wts[k] * kernel(pts[k]);
                const double ratio = q / mid;
                if (std::abs(ratio - 1.0) <= 0.25) expected = f * ratio;
            }
            const accuracy::SenderQuadrature::Entry e = rule.rescale(j, f);
            EXPECT_EQ(e.value, expected) << "row " << i << " column " << j;
            ++checked;
            applied += e.rescaled;
        }
    }
    // Both branches are exercised: rescaled entries, and ones left alone (kernel 0 at the centre).
    EXPECT_GT(checked, 1000u);
    EXPECT_GT(applied, 100u);
    EXPECT_LT(applied, checked);
}

}  // namespace
}  // namespace ffcube
