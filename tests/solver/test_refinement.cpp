// The refinement indicator and marking (solver/refinement.hpp) on radiosity fields whose variation
// is known: a step (a shadow boundary), a linear ramp, a constant (the furnace); the centroid defect on
// a plate lit by a point source (closed form).
#include <gtest/gtest.h>

#include <glm/geometric.hpp>

#include <array>
#include <cmath>

#include "ffcube/geometry/analytic.hpp"
#include "ffcube/solver/refinement.hpp"
#include "support/scenes.hpp"

namespace ffcube {
namespace {

// The unit floor as n × n patches of side h = 1/n (the mesher's grid: patch j·n + i has its centroid at
// ((i + ½)h, (j + ½)h)), and a wall that is another object.
constexpr int kN = 10;
Scene floor_and_wall() {
    NamedPolygon wall{"wall", {Vec3(0, 0, 0), Vec3(0, 1, 0), Vec3(0, 1, 1), Vec3(0, 0, 1)}};
    return test::make_scene({test::square_z("floor", 0.0, true), wall}, 1.0 / kN);
}

std::vector<Vec3> field(const Scene& s, double (*f)(const Vec3&)) {
    std::vector<Vec3> b;
    for (const Patch& p : s.patches) b.push_back(Vec3(p.object == 0 ? f(p.centroid) : 5.0));
    return b;
}

TEST(RefinementIndicator, AShadowBoundaryIsWhereTheVariationIs) {
    const Scene s = floor_and_wall();
    ASSERT_EQ(s.size(), 2u * kN * kN);
    // Lit (1) left of x = 0.5, shadow (0.2) right of it: the boundary runs between columns 4 and 5.
    const auto step = [](const Vec3& c) { return c.x < 0.5 ? 1.0 : 0.2; };
    const std::vector<Vec3> b = field(s, step);
    const std::vector<double> v = radiosity_variation(s, b);
    for (std::uint32_t i = 0; i < s.size(); ++i) {
        const Patch& p = s.patches[i];
        if (p.object != 0) {
            // Constant on the wall; the floor's values never count (another object).
            EXPECT_EQ(v[i], 0.0);
            continue;
        }
        const int col = static_cast<int>(p.centroid.x * kN);
        // Half the jump (|1 − 0.2| / 2, luminance of a grey is its value) beside the boundary, 0 elsewhere.
        EXPECT_NEAR(v[i], (col == 4 || col == 5) ? 0.4 : 0.0, 1e-12) << "column " << col;
    }
    // Marking takes the boundary's patches first, and only as many as the budget holds.
    const RefinementChoice all = choose_refinement(s, b, 1e-3, 10'000);
    EXPECT_EQ(all.candidates, 2u * kN);
    EXPECT_EQ(all.marked, 2u * kN);
    EXPECT_EQ(all.elements_after, s.size() + 3 * 2 * kN);
    const RefinementChoice some = choose_refinement(s, b, 1e-3, s.size() + 3 * 5);
    EXPECT_EQ(some.marked, 5u);
    EXPECT_TRUE(some.budget_limited);
    // Dörfler's bulk: the 20 boundary patches hold equal shares of Σ η, so 24% of it takes 5 of them
    // (4 hold 20%, the fifth brings 25%).
    const RefinementChoice bulk = choose_refinement(s, b, 1e-3, 10'000, 2, 0.24);
    EXPECT_EQ(bulk.marked, 5u);
    EXPECT_FALSE(bulk.budget_limited);
    for (std::uint32_t i = 0; i < s.size(); ++i) {
        if (some.split[i] == 1) continue;
        EXPECT_EQ(some.split[i], 2u);
        const int col = static_cast<int>(s.patches[i].centroid.x * kN);
        EXPECT_TRUE(col == 4 || col == 5);
    }
}

TEST(RefinementIndicator, ALinearRampVariesByHalfItsStepAndAConstantNotAtAll) {
    const Scene s = floor_and_wall();
    // B = 1 + 2x: neighbours (edge or corner) differ by at most 2h in x: variation h = 0.1 everywhere.
    const std::vector<double> ramp = radiosity_variation(s, field(s, [](const Vec3& c) { return 1.0 + 2.0 * c.x; }));
    // The furnace: constant B, nothing varies and nothing is marked whatever the target.
    const std::vector<Vec3> flat = field(s, [](const Vec3&) { return 3.0; });
    const std::vector<double> none = radiosity_variation(s, flat);
    for (std::uint32_t i = 0; i < s.size(); ++i) {
        // Rounding of the centroids (1e-16) times the slope, far below 1e-12.
        if (s.patches[i].object == 0) {
            EXPECT_NEAR(ramp[i], 1.0 / kN, 1e-12);
        }
        EXPECT_EQ(none[i], 0.0);
    }
    const RefinementChoice c = choose_refinement(s, flat, 1e-9, 10'000);
    EXPECT_EQ(c.candidates, 0u);
    EXPECT_EQ(c.marked, 0u);
    // The ramp's relative variation 0.1 / mean 2 = 5%: candidates at a 1% target, none at 10%.
    const std::vector<Vec3> rb = field(s, [](const Vec3& p) { return 1.0 + 2.0 * p.x; });
    EXPECT_EQ(choose_refinement(s, rb, 0.01, 10'000).candidates, std::size_t{kN * kN});
    EXPECT_EQ(choose_refinement(s, rb, 0.1, 10'000).candidates, 0u);
}

}  // namespace
}  // namespace ffcube

namespace ffcube {
namespace {

TEST(RefinementMarking, PerObjectBulkReachesAnObjectWithSmallerJumps) {
    // The floor has a step (jump 0.8 at x = 0.5), the wall a small step (jump 0.08 at z = 0.5): 20
    // boundary patches on each, η = 0.4 a on the floor's and 0.04 a on the wall's (a = patch area),
    // Σ η = 8.8 a. A global bulk of 42% (3.7 a) takes 10 floor patches (4.0 a) and nothing on the wall.
    const Scene s = floor_and_wall();
    std::vector<Vec3> b;
    for (const Patch& p : s.patches)
        b.push_back(Vec3(p.object == 0 ? (p.centroid.x < 0.5 ? 1.0 : 0.2) : (p.centroid.z < 0.5 ? 1.0 : 0.92)));
    const auto on_wall = [&](const RefinementChoice& c) {
        std::size_t n = 0;
        for (std::uint32_t i = 0; i < s.size(); ++i) n += c.split[i] > 1 && s.patches[i].object == 1;
        return n;
    };
    const RefinementChoice global = choose_refinement(s, b, 1e-3, 10'000, 2, 0.42);
    EXPECT_EQ(global.candidates, 4u * kN);
    EXPECT_EQ(global.marked, 10u);
    EXPECT_EQ(on_wall(global), 0u);
    // Per object: 42% of each object's own Σ η (3.36 a of 8 a, 0.336 a of 0.8 a): 9 patches on each.
    const RefinementChoice both = choose_refinement(s, b, 1e-3, 10'000, 2, 0.42, {true, true});
    EXPECT_EQ(both.marked, 18u);
    EXPECT_EQ(on_wall(both), 9u);
    // Only a flagged object's patches are candidates.
    const RefinementChoice wall = choose_refinement(s, b, 1e-3, 10'000, 2, 0.42, {false, true});
    EXPECT_EQ(wall.candidates, 2u * kN);
    EXPECT_EQ(wall.marked, 9u);
    EXPECT_EQ(on_wall(wall), 9u);
}

// A plate lit by a point-like source: the unit square at z = 0, the source at (0.5, 0.5, d) facing
// down. The irradiance density is f(x) = d² / (π r⁴) (cos θ cos θ' / (π r²) with both cosines d / r),
// whose exact mean over a patch is the point-to-polygon form factor divided by the area
// (geometry/analytic.hpp, ff_point_polygon, closed form). B sampled at the centroids (what a hemicube
// at each patch's centre gives) then misses the plate's mean by a known amount, which the estimator
// must predict.
struct PlateStudy {
    double actual = 0.0;     // Σ A_i (f(c_i) − mean_i f), the plate's error
    double estimated = 0.0;  // Σ A_i δ_i from centroid_defect
    std::size_t fitted = 0;
};

PlateStudy plate_study(int n, double d) {
    const Scene s = test::make_scene({test::square_z("plate", 0.0, true)}, 1.0 / n);
    EXPECT_EQ(s.size(), static_cast<std::size_t>(n * n));
    const Vec3 source(0.5, 0.5, d);
    std::vector<Vec3> b;
    PlateStudy out;
    for (std::size_t i = 0; i < s.size(); ++i) {
        const Patch& p = s.patches[i];
        const double r2 = glm::dot(p.centroid - source, p.centroid - source);
        const double f = d * d / (M_PI * r2 * r2);
        b.push_back(Vec3(f));
        const std::array<Vec3, 4> c = s.patch_vertices(i);
        const double exact = ff_point_polygon(source, Vec3(0, 0, -1), std::span<const Vec3>(c.data(), p.count));
        out.actual += p.area * f - exact;
    }
    const std::vector<Vec3> delta = centroid_defect(s, b, &out.fitted);
    for (std::size_t i = 0; i < s.size(); ++i) out.estimated += s.patches[i].area * delta[i].g;
    return out;
}

TEST(CentroidDefect, PredictsTheErrorOfCentroidValuesOnAPlateLitByAPointSource) {
    const double d = 0.5;
    const PlateStudy coarse = plate_study(16, d), fine = plate_study(32, d);
    // Every patch is fitted (border patches from two rings of neighbours).
    EXPECT_EQ(coarse.fitted, 16u * 16u);
    EXPECT_EQ(fine.fitted, 32u * 32u);
    // The error is second order: the centroid rule misses h²/24 ∇²f per unit area, and the
    // next term is O(h⁴) (relative (h/d)², 1% at n = 16): halving h divides it by 4 within 5%.
    ASSERT_NE(fine.actual, 0.0);
    EXPECT_NEAR(coarse.actual / fine.actual, 4.0, 0.2);
    // The estimate is the h² term: off by the O(h⁴) term (relative (h/d)²: 1.6% at n = 16, 0.4% at
    // n = 32) and by the one-sided fits on the border (4n of the n² patches, their Hessian off by
    // O(h/d): (4/n)(h/d) = 3.1% at n = 16, 0.8% at n = 32). Sums: 4.7% and 1.2%.
    EXPECT_NEAR(coarse.estimated / coarse.actual, 1.0, 0.047) << coarse.estimated << " vs " << coarse.actual;
    EXPECT_NEAR(fine.estimated / fine.actual, 1.0, 0.012) << fine.estimated << " vs " << fine.actual;
}

}  // namespace
}  // namespace ffcube
