// View factors to the Tregenza sky patches (raycast/sky_patches.hpp) against closed forms: the
// patches tile the upper hemisphere; an unobstructed horizontal patch gets (1/2π) Δaz (sin² alt1 −
// sin² alt0) from each, summing to 1; a tilted one sums to (1 + cos β)/2; a long wall takes the
// closed-form share of a horizontal element's sky.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <numbers>

#include "ffcube/raycast/sky_patches.hpp"
#include "support/scenes.hpp"

namespace ffcube {
namespace {

constexpr double kPi = std::numbers::pi;

// One patch per polygon (as --no-subdivide).
Scene whole_faces(const std::vector<NamedPolygon>& polys) {
    MeshOptions o;
    o.subdivide = false;
    return build_scene(model_from_polygons(polys, "<test scene>"), o);
}

// The horizontal patch's analytic view factor of a sky cell: ∫ sin(alt) dω / π.
double horizontal_vf(double a0, double a1, double f0, double f1) {
    return (f1 - f0) * (std::pow(std::sin(a1), 2) - std::pow(std::sin(a0), 2)) / (2.0 * kPi);
}

TEST(SkyPatches, TregenzaHas145PatchesTilingTheUpperHemisphere) {
    const std::vector<SkyPatch> sky = tregenza_patches();
    ASSERT_EQ(sky.size(), 145u);
    double omega = 0.0;  // Σ Δaz (sin alt1 − sin alt0) = 2π for the hemisphere
    for (const SkyPatch& p : sky) {
        EXPECT_LT(p.alt0, p.alt1);
        EXPECT_LT(p.az0, p.az1);
        omega += (p.az1 - p.az0) * (std::sin(p.alt1) - std::sin(p.alt0));
    }
    EXPECT_NEAR(omega, 2.0 * kPi, 1e-12);
    EXPECT_NEAR(sky.back().alt0, 84.0 * kPi / 180.0, 1e-15);
    EXPECT_NEAR(sky.back().alt1, kPi / 2.0, 1e-15);
}

TEST(SkyPatches, AnUnobstructedHorizontalPatchGetsTheAnalyticViewFactors) {
    const Scene scene = whole_faces({test::square_z("ground", 0.0, true)});
    ASSERT_EQ(scene.size(), 1u);
    const std::vector<SkyPatch> sky = tregenza_patches();
    const SkyPatchViewFactors v = sky_patch_view_factors(scene, sky);
    double sum = 0.0;
    for (std::size_t p = 0; p < sky.size(); ++p) {
        // The cells are exact for a horizontal patch (no cell crosses its plane): rounding only.
        EXPECT_NEAR(v.v[p], horizontal_vf(sky[p].alt0, sky[p].alt1, sky[p].az0, sky[p].az1), 1e-15) << "patch " << p;
        sum += v.v[p];
    }
    EXPECT_NEAR(sum, 1.0, 1e-13);  // the sky view factor of an unobstructed horizontal patch
}

TEST(SkyPatches, AnUnobstructedTiltedPatchSeesTheSkyOfItsTilt) {
    // A unit square tilted by β = 35° about the x axis (normal (0, −sin β, cos β)): the share of its
    // hemisphere above the horizon is (1 + cos β)/2. The horizon plane cuts cells, which are halved
    // 4 times: each leaf still cut is at most 6°/16 = 6.5e-3 rad across, so it miscounts at most
    // its solid angle (≤ 4.3e-5 sr) × |n·d| ≤ 6.5e-3, over π; the cut runs along a half great circle
    // (length π) through at most π / 6.5e-3 × 2 = 970 leaves: ≤ 970 × 4.3e-5 × 6.5e-3 / π = 8.6e-5.
    const double b = 35.0 * kPi / 180.0;
    NamedPolygon p{"tilted", {{0, 0, 0}, {1, 0, 0}, {1, std::cos(b), std::sin(b)}, {0, std::cos(b), std::sin(b)}}};
    const Scene scene = whole_faces({p});
    ASSERT_EQ(scene.size(), 1u);
    ASSERT_NEAR(scene.patches[0].normal.z, std::cos(b), 1e-12);
    const SkyPatchViewFactors v = sky_patch_view_factors(scene, tregenza_patches());
    double sum = 0.0;
    for (const double x : v.v) sum += x;
    EXPECT_NEAR(sum, (1.0 + std::cos(b)) / 2.0, 8.6e-5);
}

// Differential horizontal element to a parallel-edged vertical rectangle in front of it: the wall
// x = d, |y| ≤ L, 0 ≤ z ≤ h, element at the origin facing up (Howell's catalogue, C-16 twice):
// F = (1/π) [atan(L/d) − d/√(d²+h²) atan(L/√(d²+h²))].
double element_to_wall(double d, double h, double L) {
    const double r = std::sqrt(d * d + h * h);
    return (std::atan(L / d) - d / r * std::atan(L / r)) / kPi;
}

TEST(SkyPatches, ALongWallTakesItsClosedFormShareOfTheSky) {
    const double d = 1.0, h = 1.0, L = 100.0, s = 0.02;
    const Scene scene = whole_faces({test::square_z("element", 0.0, true, s, Vec3(-s / 2, -s / 2, 0)),
                                     {"wall", {{d, -L, 0}, {d, -L, h}, {d, L, h}, {d, L, 0}}}});
    ASSERT_EQ(scene.size(), 2u);
    const std::vector<SkyPatch> sky = tregenza_patches();
    const SkyPatchViewFactors v = sky_patch_view_factors(scene, sky);
    double sum = 0.0;
    for (std::size_t p = 0; p < sky.size(); ++p) sum += v.v[p];
    const double want = 1.0 - element_to_wall(d, h, L);
    // Each traced cell (a Tregenza patch cut 2 × 2) counts as wholly open or blocked from each
    // sample point; only the cells the wall's top edge (or its ends) crosses can be miscounted. The
    // tolerance is the total weight of the cells the edge alt(az) = atan(h sin(az') / d) crosses
    // (az' measured from the wall's normal, +x: az = 90°), computed here, plus 1e-4 for the
    // element's 0.02 width (the first-order change across it cancels about its centre).
    double bound = 1e-4;
    for (const SkyPatch& p : sky)
        for (int ka = 0; ka < 2; ++ka)
            for (int kf = 0; kf < 2; ++kf) {
                const double a0 = p.alt0 + ka * (p.alt1 - p.alt0) / 2, a1 = a0 + (p.alt1 - p.alt0) / 2;
                const double f0 = p.az0 + kf * (p.az1 - p.az0) / 2, f1 = f0 + (p.az1 - p.az0) / 2;
                double lo = kPi, hi = -kPi;  // the edge's altitude range over the cell's azimuths
                for (int k = 0; k <= 64; ++k) {
                    const double c = std::sin(f0 + (f1 - f0) * k / 64.0);  // cos of the angle from +x
                    const double alt = c > 0.0 ? std::atan(h * c / d) : 0.0;
                    lo = std::min(lo, alt), hi = std::max(hi, alt);
                }
                if (hi > a0 && lo < a1) bound += horizontal_vf(a0, a1, f0, f1);
            }
    EXPECT_NEAR(sum, want, bound) << "bound " << bound;
    EXPECT_LT(bound, 0.07);  // the bound itself is a real check, not a free pass
    std::printf("long wall: sky view %.6f, closed form %.6f, bound %.4f\n", sum, want, bound);
    EXPECT_GT(v.rays, 0u);
}

TEST(SkyPatches, TheSameBitsForOneOrManyThreads) {
    std::vector<NamedPolygon> polys = {{"wall", {{1, -3, 0}, {1, -3, 1}, {1, 3, 1}, {1, 3, 0}}}};
    for (int k = 0; k < 6; ++k) polys.push_back(test::square_z("g" + std::to_string(k), 0.0, true, 0.5, Vec3(-k * 0.5, 0, 0)));
    const Scene scene = whole_faces(polys);
    SkyPatchOptions one, three;
    one.threads = 1;
    three.threads = 3;
    const std::vector<SkyPatch> sky = tregenza_patches();
    EXPECT_EQ(sky_patch_view_factors(scene, sky, one).v, sky_patch_view_factors(scene, sky, three).v);
}

}  // namespace
}  // namespace ffcube
