// `--exact-visibility auto` (NearFieldOptions::exact_visibility_budget, docs/accuracy.md "Exact
// visibility past a few occluders"): the per-row budget in point evaluations × occluders, on a
// scene built so that the row's refused pairs need more than a given budget. The counts follow
// from the adaptive rule's own point counts (deterministic: they depend on the geometry only).
#include <gtest/gtest.h>

#include <limits>

#include "ffcube/accuracy/near_field.hpp"
#include "ffcube/geometry/visible_ff.hpp"
#include "ffcube/scene/mesher.hpp"
#include "ffcube/scene/polygons.hpp"
#include "support/scenes.hpp"

namespace ffcube {
namespace {

Scene make(const std::vector<NamedPolygon>& polys) {
    return test::make_scene(polys, 1e9);  // one patch per polygon
}

// A sender 0.1 wide on the ground, a low kerb 0.3 in front of it (faces −x, 0.3 tall, 0.2 wide,
// so that its ends' shadows sweep across the walls' edges and each pair's rule refines), and behind it three wall pieces in the plane x = 0.65 (faces −x): each wall piece is within 10
// sender sizes of the sender (so its pair asks for sub-hemicubes) and its shaft holds the kerb
// (one possible occluder), so all three are refused and eligible.
Scene kerb_scene() {
    const double x = 0.65, kerb = 0.35;
    return make({
        {"sender", {{-0.05, -0.05, 0}, {0.05, -0.05, 0}, {0.05, 0.05, 0}, {-0.05, 0.05, 0}}},
        {"kerb", {{kerb, -0.1, 0}, {kerb, -0.1, 0.3}, {kerb, 0.1, 0.3}, {kerb, 0.1, 0}}},
        {"wall a", {{x, -5, 0}, {x, -5, 4}, {x, -0.2, 4}, {x, -0.2, 0}}},
        {"wall b", {{x, -0.2, 0}, {x, -0.2, 4}, {x, 0.2, 4}, {x, 0.2, 0}}},
        {"wall c", {{x, 0.2, 0}, {x, 0.2, 4}, {x, 5, 4}, {x, 5, 0}}},
    });
}

// row_budget: the row's, in evaluations × occluders. The option is per hemicube spared: this
// row, once its pairs are exact, is one hemicube (no far field, no occluder beside it) instead of
// 2 × 2 sub-hemicubes, so it spares 3 (0: no bound, an explicit K).
NearFieldOptions options(double row_budget) {
    NearFieldOptions o;
    o.exact_visibility_occluders = kAutoExactVisibilityOccluders;
    o.exact_visibility_budget = row_budget / 3;
    // The kerb stands beside the sender with the walls behind it, which asks for sub-hemicubes on
    // its own (docs/accuracy.md, "Senders beside an occluder"), and auto then tries nothing (the
    // row is sampled anyway): this test is about the budget alone.
    o.sample_beside_occluders = false;
    return o;
}

struct Planned {
    NearAnalysis a;
    RowProvider::RowPlan plan;
};

Planned plan(const Scene& s, double budget) {
    const NearFieldCorrector c(s, options(budget));
    Planned r;
    NearFieldScratch scratch;
    r.plan = c.plan_row(0, r.a, scratch);
    return r;
}

TEST(ExactVisibilityAuto, TheBudgetLeavesPairsRefusedByADeterministicCount) {
    const Scene s = kerb_scene();
    ASSERT_EQ(s.size(), 5u);
    // No bound: all three pairs exact, the row needs no sub-hemicubes.
    const Planned all = plan(s, 0);
    ASSERT_EQ(all.a.exact_visibility, 3u);
    EXPECT_EQ(all.a.refused_sampled, 0u);
    EXPECT_EQ(all.a.exact_visibility_over_budget, 0u);
    EXPECT_EQ(all.plan, RowProvider::RowPlan::centre);
    const std::uint64_t points = all.a.exact_visibility_points;
    const double cost = all.a.exact_visibility_cost;  // points × each pair's possible occluders
    // Each pair's least cost: the sender's front part is the whole quad, 2 fan triangles.
    const auto least = static_cast<double>(visible_ff_min_points(4));
    ASSERT_EQ(least, 2 * 16 * 80);
    ASSERT_GE(cost, static_cast<double>(points));  // at least one occluder each (the kerb)
    ASSERT_GT(static_cast<double>(points), 3 * least);  // the pairs refine beyond their start

    // A budget of what they took plus one split's margin (the rule splits a cell, 64 points, only
    // with 256 points left: 256 × at most 8 occluders): the same values, none refused (auto's
    // rule is the explicit one's, only capped).
    const Planned enough = plan(s, cost + 256.0 * kAutoExactVisibilityOccluders);
    EXPECT_EQ(enough.a.exact_visibility, 3u);
    EXPECT_EQ(enough.a.exact_visibility_points, points);
    EXPECT_EQ(enough.a.exact, all.a.exact);
    EXPECT_EQ(enough.a.exact_visibility_over_budget, 0u);
    EXPECT_EQ(enough.plan, RowProvider::RowPlan::centre);

    // Below the three least costs together (each at least `least`, one occluder or more):
    // nothing is tried (no point spent), all three stay refused, the row keeps its sub-hemicubes.
    const Planned none = plan(s, 3 * least - 1);
    EXPECT_EQ(none.a.exact_visibility, 0u);
    EXPECT_EQ(none.a.exact_visibility_points, 0u);
    EXPECT_EQ(none.a.exact_visibility_over_budget, 3u);
    EXPECT_EQ(none.a.refused_sampled, 3u);
    EXPECT_EQ(none.plan, RowProvider::RowPlan::sampled);

    // One unit short of what all three take: the first two are made as before (they fit with
    // the third's points to spare); the third's rule is capped at one point fewer than it took,
    // below its last split, so it does not converge and stays refused, counted as over budget.
    const Planned short_one = plan(s, cost - 1);
    EXPECT_EQ(short_one.a.exact_visibility, 2u);
    EXPECT_EQ(short_one.a.exact_visibility_over_budget, 1u);
    EXPECT_EQ(short_one.a.exact_visibility_unconverged, 0u);
    EXPECT_EQ(short_one.a.refused_sampled, 1u);
    EXPECT_LT(short_one.a.exact_visibility_cost, cost);
    EXPECT_EQ(short_one.plan, RowProvider::RowPlan::sampled);
}

// Where the row is sampled anyway (the kerb beside the sender), auto tries nothing: sub-hemicubes
// measure those pairs, and exact values would only add cost. An explicit K still makes them.
TEST(ExactVisibilityAuto, NothingIsTriedWhereTheRowIsSampledAnyway) {
    const Scene s = kerb_scene();
    NearFieldOptions o = options(std::numeric_limits<double>::max());
    o.sample_beside_occluders = true;
    {
        const NearFieldCorrector c(s, o);
        NearAnalysis a;
        NearFieldScratch scratch;
        EXPECT_NE(c.plan_row(0, a, scratch), RowProvider::RowPlan::centre);
        EXPECT_GT(a.occluder, 0);
        EXPECT_EQ(a.exact_visibility, 0u);
        EXPECT_EQ(a.exact_visibility_points, 0u);
        EXPECT_EQ(a.refused_sampled, 3u);
        EXPECT_EQ(c.exact_visibility_mode(), "auto");
    }
    o.exact_visibility_budget = 0;
    const NearFieldCorrector c(s, o);
    NearAnalysis a;
    NearFieldScratch scratch;
    c.plan_row(0, a, scratch);
    EXPECT_EQ(a.exact_visibility, 3u);
    EXPECT_EQ(c.exact_visibility_mode(), "8");
}

}  // namespace
}  // namespace ffcube
