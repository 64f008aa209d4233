// Accuracy by target (RaycastOptions::tolerance, docs/accuracy.md "Accuracy by target"): rows
// refined by replicated scrambled nets, their estimates checked against exact rows.
//
// The reference: the scenes have no occluders, so every entry F_ij is the closed-form polygon
// factor ff_polygon_polygon (error ≲ 1e-12 relative, far below the 1e-3 target) and the row's
// sum is their sum. A row's true error is the larger of its largest entry error and its sum
// error, the quantity the estimate bounds.
//
// What is asserted is issue 40's honesty rule: at least 95% of the rows have a true error at or
// below their estimate and none more than 3 times it; and that refining works: a row stops as
// soon as its estimate meets the target, with at least tolerance_rays(E).least rays, and a row
// whose estimate is still above it has spent its whole budget and is counted. The rows are fixed by the seed,
// so the test is deterministic; it fails if the estimate is made optimistic (a smaller t, fewer
// replicates treated as independent, a missing rule-of-three floor).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <mutex>
#include <vector>

#include "ffcube/core/error.hpp"
#include "ffcube/raycast/raycast_provider.hpp"
#include "support/exact_rows.hpp"
#include "support/scenes.hpp"

namespace ffcube {
namespace {

using test::NamedPolygon;

struct Checked {
    std::size_t rows = 0, covered = 0, above = 0;
    double worst_ratio = 0, largest_estimate = 0;
};

// Every row of `scene` refined to E against the closed forms.
Checked check_rows(const Scene& scene, double E) {
    RaycastOptions o;
    o.tolerance = E;
    o.threads = 2;
    RaycastRowProvider provider(scene, o);
    const std::uint32_t n = provider.size();
    std::vector<std::uint32_t> rows(n);
    for (std::uint32_t i = 0; i < n; ++i) rows[i] = i;
    std::vector<double> estimate(n, -1), rays(n, 0);
    std::vector<SparseRow> got(n);
    RowProvider::RowStages stages;
    stages.measured = [&](std::size_t, std::uint32_t i, double e, double r) { estimate[i] = e, rays[i] = r; };
    provider.compute_rows_staged(rows, stages, [&](std::uint32_t i, const SparseRow& r) { got[i] = r; });
    Checked c;
    for (std::uint32_t i = 0; i < n; ++i) {
        const double truth = test::unoccluded_row_error(scene, i, got[i]);
        EXPECT_GT(estimate[i], 0.0) << "row " << i << ": no estimate";
        ++c.rows;
        c.covered += truth <= estimate[i];
        c.worst_ratio = std::max(c.worst_ratio, truth / estimate[i]);
        c.largest_estimate = std::max(c.largest_estimate, estimate[i]);
        const RayBudget b = tolerance_rays(E);
        EXPECT_GE(rays[i], static_cast<double>(b.least)) << "row " << i;
        if (estimate[i] > E) {
            ++c.above;
            EXPECT_EQ(rays[i], static_cast<double>(b.most)) << "row " << i << " stopped above the target";
        }
    }
    EXPECT_EQ(provider.stats().refined_rows, n);
    EXPECT_EQ(provider.stats().rows_at_budget, c.above);
    return c;
}

TEST(RaycastTolerance, EstimatesCoverTheTrueErrorOfExactRows) {
    const double E = 1e-3;
    // Facing squares, perpendicular squares and a tilted pair: entries from 0.2 down to 1e-3.
    const std::vector<Scene> scenes = {
        test::make_scene({test::square_z("a", 0.0, true), test::square_z("b", 1.0, false)}, 0.25),
        test::make_scene({{"floor", {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}}},
                          {"wall", {{0, 0, 0}, {0, 1, 0}, {0, 1, 1}, {0, 0, 1}}}},
                         0.25),
        test::make_scene({{"low", {{0, 0, 0}, {2, 0, 0}, {2, 1, 0}, {0, 1, 0}}},
                          {"tilted", {{0.5, 0, 1.5}, {0.5, 1, 1.5}, {1.5, 1, 0.8}, {1.5, 0, 0.8}}}},
                         0.3),
    };
    Checked all;
    for (const Scene& s : scenes) {
        const Checked c = check_rows(s, E);
        all.rows += c.rows, all.covered += c.covered, all.above += c.above;
        all.worst_ratio = std::max(all.worst_ratio, c.worst_ratio);
        all.largest_estimate = std::max(all.largest_estimate, c.largest_estimate);
    }
    ASSERT_GE(all.rows, 80u);
    std::printf("%zu of %zu rows within their estimate, largest true/estimate %.2f, largest estimate %.3g, %zu above "
                "the target at their budget\n",
                all.covered, all.rows, all.worst_ratio, all.largest_estimate, all.above);
    EXPECT_GE(static_cast<double>(all.covered), 0.95 * static_cast<double>(all.rows))
        << all.covered << " of " << all.rows << " rows within their estimate";
    EXPECT_LE(all.worst_ratio, 3.0);
    // Most rows meet the target within the budget of 64/E rays: 26 of 112 did not when this was
    // written (rows of the touching pair, whose largest entries are large); a third or more would
    // mean the estimate or the doubling had gone wrong. Each was checked above to have spent its
    // whole budget.
    EXPECT_LT(static_cast<double>(all.above), static_cast<double>(all.rows) / 3.0);
}

TEST(RaycastTolerance, RowsAreTheSameForAnyThreadCount) {
    const Scene scene = test::make_scene({test::square_z("a", 0.0, true), test::square_z("b", 1.0, false)}, 0.5);
    std::vector<SparseRow> rows[2];
    for (unsigned t : {1u, 2u}) {
        RaycastOptions o;
        o.tolerance = 1e-3;
        o.threads = t;
        RaycastRowProvider provider(scene, o);
        std::vector<std::uint32_t> list(provider.size());
        for (std::uint32_t i = 0; i < provider.size(); ++i) list[i] = i;
        rows[t - 1].resize(provider.size());
        provider.compute_rows(list, [&](std::uint32_t i, const SparseRow& r) { rows[t - 1][i] = r; });
    }
    for (std::size_t i = 0; i < rows[0].size(); ++i) {
        EXPECT_EQ(rows[0][i].col, rows[1][i].col);
        EXPECT_EQ(rows[0][i].val, rows[1][i].val);
    }
}

TEST(RaycastTolerance, TheBudgetFollowsTheTarget) {
    // At least 3/E rays (the rule of three) and 4,096; at most 64/E and 2^24; powers of two.
    EXPECT_EQ(tolerance_rays(1e-3).least, 4096u);
    EXPECT_EQ(tolerance_rays(1e-3).most, 65536u);
    EXPECT_EQ(tolerance_rays(1e-4).least, 32768u);
    EXPECT_EQ(tolerance_rays(1e-4).most, 1048576u);
    EXPECT_EQ(tolerance_rays(1e-6).most, std::uint64_t{1} << 24);
    RaycastOptions o;
    o.tolerance = -1;
    const Scene scene = test::make_scene({test::square_z("a", 0.0, true)}, 0.5);
    EXPECT_THROW(RaycastRowProvider(scene, o), InputError);
}

}  // namespace
}  // namespace ffcube
