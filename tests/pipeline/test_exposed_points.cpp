// Senders cut by a facet (accuracy/exposed_points.hpp, docs/accuracy.md "Senders cut by a facet"): a
// square ground patch half inside a closed box that stands on it. The exposed half's points lie
// outside the box, their weights integrate the quadratics over that half exactly, and the row
// measured at them matches the closed form of the exposed half's factor to the box's wall.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <numbers>
#include <string>
#include <vector>

#include "ffcube/reference/closed_forms.hpp"
#include "ffcube/geometry/analytic.hpp"
#include "ffcube/accuracy/near_field.hpp"
#include "ffcube/geometry/quadrature.hpp"
#include "ffcube/gl/hemicube_provider.hpp"
#include "accuracy/exposed_points.hpp"
#include "support/scenes.hpp"

namespace ffcube {
namespace {

// The closed box [x0,x1]×[y0,y1]×[z0,z1], faces outward ("west" is x = x0).
std::vector<NamedPolygon> box_outward(double x0, double x1, double y0, double y1, double z0, double z1) {
    return {
        {"west", {{x0, y0, z0}, {x0, y0, z1}, {x0, y1, z1}, {x0, y1, z0}}},
        {"east", {{x1, y0, z0}, {x1, y1, z0}, {x1, y1, z1}, {x1, y0, z1}}},
        {"south", {{x0, y0, z0}, {x1, y0, z0}, {x1, y0, z1}, {x0, y0, z1}}},
        {"north", {{x0, y1, z0}, {x0, y1, z1}, {x1, y1, z1}, {x1, y1, z0}}},
        {"bottom", {{x0, y0, z0}, {x0, y1, z0}, {x1, y1, z0}, {x1, y0, z0}}},
        {"top", {{x0, y0, z1}, {x1, y0, z1}, {x1, y1, z1}, {x0, y1, z1}}},
    };
}

// Ground [-1,1]² at z = 0 facing up (object 0), the box [0,2]×[-1,1]×[0,1] standing on its half
// x > 0 (its west wall, object 1, rises across the ground's middle). One patch per polygon.
struct HalfInBox {
    Scene scene;
    std::uint32_t ground = 0, west = 0, top = 0;
    HalfInBox() {
        std::vector<NamedPolygon> polys{{"ground", {{-1, -1, 0}, {1, -1, 0}, {1, 1, 0}, {-1, 1, 0}}}};
        for (auto& p : box_outward(0, 2, -1, 1, 0, 1)) polys.push_back(p);
        scene = test::make_scene(polys, 1e9);
        for (std::uint32_t p = 0; p < scene.size(); ++p) {
            const std::uint32_t o = scene.patches[p].object;
            if (o == 0) ground = p;
            if (o == 1) west = p;
            if (o == 6) top = p;
        }
    }
};

TEST(ExposedPoints, PolygonMomentsOfTheUnitSquare) {
    const std::vector<std::array<double, 2>> sq{{0, 0}, {1, 0}, {1, 1}, {0, 1}};
    const Moments m = polygon_moments(sq);
    const Moments want{1, 0.5, 0.5, 1.0 / 3, 0.25, 1.0 / 3};
    for (std::size_t r = 0; r < 6; ++r) EXPECT_NEAR(m[r], want[r], 1e-15) << r;
}

TEST(ExposedPoints, OnlyTheCutSenderIsCut) {
    const HalfInBox h;
    const ExposedPoints e(h.scene);
    EXPECT_TRUE(e.cut(h.ground));
    // The box's faces: the ground meets none of them inside (the bottom lies in the ground's
    // plane, the walls stand on the bottom's edges).
    for (std::uint32_t p = 0; p < h.scene.size(); ++p) {
        if (p == h.ground) continue;
        EXPECT_FALSE(e.cut(p)) << "patch " << p;
    }
    std::vector<Vec3> points;
    std::vector<double> weights;
    EXPECT_FALSE(e.rule(h.top, points, weights));
}

// The 32 × 32 cells' boundaries include x = 0, so the exposed cells make up the half x < 0
// exactly, and the fitted weights reproduce its moments over the patch's area 4:
// ∫1 = 2, ∫x = −1, ∫y = 0, ∫x² = 2/3, ∫xy = 0, ∫y² = 2/3. Only rounding is left (the 6 × 6
// solve and the sums, in units of the patch: well under 1e-12), asserted to 1e-9.
TEST(ExposedPoints, PointsOutsideTheBoxWeightsExactForQuadratics) {
    const HalfInBox h;
    const ExposedPoints e(h.scene);
    std::vector<Vec3> points;
    std::vector<double> weights;
    ASSERT_TRUE(e.rule(h.ground, points, weights));
    ASSERT_EQ(points.size(), static_cast<std::size_t>(ExposedPoints::kPoints));
    Moments sum{};
    for (std::size_t q = 0; q < points.size(); ++q) {
        EXPECT_LT(points[q].x, 0.0) << "point " << q << " inside the box";
        EXPECT_NEAR(points[q].z, 0.0, 1e-12);
        const Moments m = monomials(points[q].x, points[q].y);
        for (std::size_t r = 0; r < 6; ++r) sum[r] += weights[q] * m[r];
    }
    const Moments want{2.0 / 4, -1.0 / 4, 0, (2.0 / 3) / 4, 0, (2.0 / 3) / 4};
    for (std::size_t r = 0; r < 6; ++r) EXPECT_NEAR(sum[r], want[r], 1e-9) << "moment " << r;
}

// The row of the ground to the west wall: only the exposed half sees the wall's front, so
// F = ½ · F(exposed half → wall), the closed form for perpendicular rectangles sharing their
// edge (l = 2 along it, w = 1, h = 1). Two errors, bounded apart:
//  - the rule on the exact point factor (ff_point_polygon): within 2e-3 of the closed form. The
//    point factor is smooth on the exposed half except for its ln-type derivative at the shared
//    edge, where it tends to ½; the exposed cells' points stand at least half a cell (1/32) off it,
//    and a degree-2 rule there errs by about the cells' share of the region times the factor's
//    spread, (1/32) × ½ × ¼ ≈ 4e-3, halved by the weights' sum ½: 2e-3.
//  - the hemicube at each point (half of 128: n = 64) against the exact point factor: a pixel on
//    the wall's outline is wrongly in or out by a fraction of it uniform in (−½, ½), at most
//    ΔF_max = 4/(π n²) each, and the outline crosses at most 4n pixels of the atlas: σ ≤
//    √(4n) ΔF_max / √12 per point, σ √(Σ w²) for the rule (the points' outlines fall on
//    different pixels); asserted within 4σ.
TEST(ExposedPoints, RowFromTheExposedHalfMatchesTheClosedForm) {
    const HalfInBox h;
    const double closed = 0.5 * ff_perpendicular_rectangles_common_edge(2, 1, 1);
    const ExposedPoints e(h.scene);
    std::vector<Vec3> points;
    std::vector<double> weights;
    ASSERT_TRUE(e.rule(h.ground, points, weights));
    const auto wall = h.scene.patch_vertices(h.west);
    double exact_points = 0, w2 = 0;
    for (std::size_t q = 0; q < points.size(); ++q) {
        exact_points += weights[q] * ff_point_polygon(points[q], Vec3(0, 0, 1), std::span<const Vec3>(wall.data(), 4));
        w2 += weights[q] * weights[q];
    }
    EXPECT_NEAR(exact_points, closed, 2e-3);

    HemicubeOptions o;
    o.resolution = 128;
    o.threads = 1;
    HemicubeRowProvider provider(h.scene, o);
    const std::vector<std::uint32_t> rows{h.ground};
    // The measure contract: the plan's sender points and weights (the rule's) in the request.
    std::vector<RowProvider::RowRequest> requests(1);
    requests[0].plan = RowProvider::RowPlan::sampled_fine;
    requests[0].points = points;
    requests[0].weights = weights;
    requests[0].partly_enclosed = true;
    double f = -1, sum = 0;
    provider.compute_rows_requested(rows, requests, [&](std::uint32_t, const SparseRow& r) {
        f = 0;
        for (std::size_t k = 0; k < r.col.size(); ++k) {
            if (r.col[k] == h.west) f = r.val[k];
            sum += r.val[k];
        }
    });
    const double n = 64, sigma = std::sqrt(4 * n) * 4 / (std::numbers::pi * n * n) / std::sqrt(12.0) * std::sqrt(w2);
    EXPECT_NEAR(f, exact_points, 4 * sigma);
    EXPECT_NEAR(sum, f, 1e-12) << "the exposed half sees nothing but the wall's front";
    EXPECT_EQ(provider.stats().partly_enclosed_rows, 1u);
    std::printf("closed %.6f, rule on exact point factors %.6f, hemicube %.6f (4 sigma %.1e)\n", closed, exact_points,
                f, 4 * sigma);
}

// A sender partly covered (accuracy::covers_part; docs/accuracy.md, "Senders partly covered"): a
// ceiling [-1,1]² at z = 1 facing down, a lamp plate just below it (gap g = 1e-4, facing down)
// over x > −0.375, a floor [-3,3]² at z = 0 facing up. The ceiling's centroid lies over the lamp:
// one hemicube there sees the lamp's back only (an empty row), while the exposed part x < −0.375
// (31.25% of the ceiling) sees the floor. The Cornell box's light hangs 0.1 below its ceiling so.
struct CoveredCeiling {
    Scene scene;
    std::uint32_t ceiling = 0, lamp = 0, floor = 0;
    static constexpr double kEdge = -0.375;  // a cell boundary of the 32 × 32 grid over [-1,1]
    explicit CoveredCeiling(double gap = 1e-4, double lamp_from = kEdge) {
        scene = test::make_scene(
            {
                {"ceiling", {{-1, -1, 1}, {-1, 1, 1}, {1, 1, 1}, {1, -1, 1}}},
                {"lamp", {{lamp_from, -2, 1 - gap}, {lamp_from, 2, 1 - gap}, {2, 2, 1 - gap}, {2, -2, 1 - gap}}},
                {"floor", {{-3, -3, 0}, {3, -3, 0}, {3, 3, 0}, {-3, 3, 0}}},
            },
            1e9);
        for (std::uint32_t p = 0; p < scene.size(); ++p) {
            const std::uint32_t o = scene.patches[p].object;
            (o == 0 ? ceiling : o == 1 ? lamp : floor) = p;
        }
    }
};

// The exposed cells are the strip x < −0.375 exactly (its edge is a cell boundary; every cell
// centre under the lamp lies at least half a cell, 1/32, inside it, far beyond g·tan 60° = 1.7e-4,
// so all five rays meet the lamp's back), and the weights reproduce the strip's moments over the
// ceiling's area 4: ∫1 = 1.25, ∫x = −(1 − 0.375²)/2 · 2, ∫y = 0, ∫x² = (1 − 0.375³)/3 · 2, ∫xy = 0,
// ∫y² = 0.625 · 2/3; only rounding is left (as above, 1e-9).
TEST(ExposedPoints, PartlyCoveredSenderHasPointsOnItsExposedStrip) {
    const CoveredCeiling h;
    const ExposedPoints e(h.scene);
    EXPECT_TRUE(e.cut(h.ceiling));
    EXPECT_FALSE(e.cut(h.floor));
    EXPECT_FALSE(e.cut(h.lamp));
    std::vector<Vec3> points;
    std::vector<double> weights;
    ASSERT_TRUE(e.rule(h.ceiling, points, weights));
    Moments sum{};
    for (std::size_t q = 0; q < points.size(); ++q) {
        EXPECT_LT(points[q].x, CoveredCeiling::kEdge) << "point " << q << " under the lamp";
        const Moments m = monomials(points[q].x, points[q].y);
        for (std::size_t r = 0; r < 6; ++r) sum[r] += weights[q] * m[r];
    }
    const double a = CoveredCeiling::kEdge;
    const Moments want{0.625 * 2 / 4, -(1 - a * a) / 2 * 2 / 4, 0, (a * a * a + 1) / 3 * 2 / 4, 0, 0.625 * (2.0 / 3) / 4};
    for (std::size_t r = 0; r < 6; ++r) EXPECT_NEAR(sum[r], want[r], 1e-9) << "moment " << r;
    // Not a cover: the lamp over the whole ceiling (nothing exposed), or farther below it than
    // accuracy::kCoverGap (half the ceiling's size 2: 1; at 1.2 it hangs under the floor, which
    // does not matter here).
    const CoveredCeiling whole(1e-4, -2), far(1.2);
    EXPECT_FALSE(ExposedPoints(whole.scene).cut(whole.ceiling));
    EXPECT_FALSE(ExposedPoints(far.scene).cut(far.ceiling));
}

// The ceiling's row to the floor: F = ¼ · 1.25 · F(strip → floor), the closed form for offset
// parallel rectangles (Howell C-12). Two errors, bounded apart:
//  - the rule on the exact point factor: it integrates quadratics exactly; the point factor to a
//    floor 6 wide at height 1 is analytic over the strip, its Taylor terms falling as (strip
//    half-width 0.31 / distance to the floor's edge, ≥ 2)^k, so the cubic remainder is below
//    F·(0.31/2)³ ≈ 3e-3 of the strip's factor, × its share 0.31: 1e-3; asserted 2e-3;
//  - the hemicube at each point against the exact point factor (half of 128: n = 64), as above:
//    asserted within 4σ. The lamp's edge, g = 1e-4 below, hides from a point δ ≥ 1/32 away only
//    directions within g/δ = 3.2e-3 rad of the horizon: a projected solid angle below
//    (g/δ)²/2 = 5e-6, well inside σ.
// Measured at the ceiling's centre alone the row would be empty, and a 4 × 4 Gauss rule over
// the whole ceiling would give the strip the weight of its one outer column, 0.17 instead of 0.31.
TEST(ExposedPoints, PartlyCoveredSenderRowMatchesTheClosedForm) {
    const CoveredCeiling h;
    const double a = CoveredCeiling::kEdge;
    const double closed = (0.625 * 2 / 4) * ff_parallel_rectangles_offset(-1, a, -1, 1, -3, 3, -3, 3, 1);
    const ExposedPoints e(h.scene);
    std::vector<Vec3> points;
    std::vector<double> weights;
    ASSERT_TRUE(e.rule(h.ceiling, points, weights));
    const auto floor = h.scene.patch_vertices(h.floor);
    double exact_points = 0, w2 = 0;
    for (std::size_t q = 0; q < points.size(); ++q) {
        exact_points += weights[q] * ff_point_polygon(points[q], Vec3(0, 0, -1), std::span<const Vec3>(floor.data(), 4));
        w2 += weights[q] * weights[q];
    }
    EXPECT_NEAR(exact_points, closed, 2e-3);

    HemicubeOptions o;
    o.resolution = 128;
    o.threads = 1;
    HemicubeRowProvider provider(h.scene, o);
    const std::vector<std::uint32_t> rows{h.ceiling};
    // The measure contract: the plan's sender points and weights (the rule's) in the request.
    std::vector<RowProvider::RowRequest> requests(1);
    requests[0].plan = RowProvider::RowPlan::sampled_fine;
    requests[0].points = points;
    requests[0].weights = weights;
    requests[0].partly_enclosed = true;
    double f = -1;
    provider.compute_rows_requested(rows, requests, [&](std::uint32_t, const SparseRow& r) {
        f = 0;
        for (std::size_t k = 0; k < r.col.size(); ++k)
            if (r.col[k] == h.floor) f = r.val[k];
    });
    const double n = 64, sigma = std::sqrt(4 * n) * 4 / (std::numbers::pi * n * n) / std::sqrt(12.0) * std::sqrt(w2);
    EXPECT_NEAR(f, exact_points, 4 * sigma);
    EXPECT_EQ(provider.stats().partly_enclosed_rows, 1u);
    std::printf("closed %.6f, rule on exact point factors %.6f, hemicube %.6f (4 sigma %.1e)\n", closed, exact_points,
                f, 4 * sigma);
}

// The plan hands the measure its sender points (the sender rule is accuracy's, gl only measures):
// through the correction, a sampled row's request carries the points and weights of
// ExposedPoints::rule where the sender is partly covered (the ceiling over the lamp) and the
// patch's quadrature points elsewhere, bit for bit; a centre row carries none. The inner
// provider only records the requests (rows empty: nothing is measured).
class RecordingRequests final : public RowProvider {
public:
    explicit RecordingRequests(std::uint32_t n) : requests(n), seen(n, 0) {}
    std::uint32_t size() const override { return static_cast<std::uint32_t>(requests.size()); }
    std::string name() const override { return "recording"; }
    bool can_sample_sender() const override { return true; }
    void compute_rows(std::span<const std::uint32_t> rows, const RowSink& sink) override {
        for (const std::uint32_t i : rows) sink(i, SparseRow{});
    }
    void compute_rows_requested(std::span<const std::uint32_t> rows, std::span<const RowRequest> given,
                                const RowSink& sink) override {
        for (std::size_t k = 0; k < rows.size(); ++k) {
            requests[rows[k]] = given[k];
            seen[rows[k]] = 1;
            sink(rows[k], SparseRow{});
        }
    }
    std::vector<RowRequest> requests;
    std::vector<int> seen;
};

TEST(ExposedPoints, ThePlanHandsTheMeasureTheExposedPoints) {
    const CoveredCeiling h;
    RecordingRequests inner(static_cast<std::uint32_t>(h.scene.size()));
    CorrectedRowProvider corrected(h.scene, inner, near_field_options_for_hemicube(128));
    compute_all_rows(corrected);
    const ExposedPoints e(h.scene);
    std::size_t sampled = 0, exposed = 0;
    for (std::uint32_t i = 0; i < h.scene.size(); ++i) {
        ASSERT_TRUE(inner.seen[i]) << "row " << i;
        const RowProvider::RowRequest& r = inner.requests[i];
        EXPECT_EQ(r.engine, RowProvider::RowEngine::provider);
        if (!r.sampled()) {
            EXPECT_TRUE(r.points.empty()) << "row " << i;
            continue;
        }
        ++sampled;
        std::vector<Vec3> points;
        std::vector<double> weights;
        if (e.rule(i, points, weights)) {
            ++exposed;
            EXPECT_TRUE(r.partly_enclosed);
        } else {
            const auto v = h.scene.patch_vertices(i);
            patch_quadrature(std::span<const Vec3>(v.data(), h.scene.patches[i].count),
                             r.plan == RowProvider::RowPlan::sampled_fine ? 4 : 2, points, weights);
            EXPECT_FALSE(r.partly_enclosed);
        }
        EXPECT_EQ(r.points, points) << "row " << i;
        EXPECT_EQ(r.weights, weights) << "row " << i;
    }
    EXPECT_EQ(inner.requests[h.ceiling].partly_enclosed, true) << "the ceiling is planned sampled, at its exposed strip";
    EXPECT_GE(sampled, exposed);
    EXPECT_EQ(exposed, 1u);
}

}  // namespace
}  // namespace ffcube
