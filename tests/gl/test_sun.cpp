// Sunlit fractions (gl/sun.hpp) against the closed form of a box's shadow on a plane
// (support/box_shadow.hpp), for ten sun positions from grazing (5°) to the zenith; tiling,
// determinism, the pixel budget and the refusals.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <glm/geometric.hpp>

#include "ffcube/core/error.hpp"
#include "ffcube/gl/sun.hpp"
#include "support/box_shadow.hpp"
#include "support/scenes.hpp"

namespace ffcube {
namespace {

using test::box_on_plane;

// Exact: the roof and the walls facing the sun are wholly lit (a convex box shades none of its own
// faces that face the sun), the walls facing away get nothing, the ground loses the shadow.
double exact_fraction(const Scene& s, std::size_t i, Vec3 sun) {
    const Patch& p = s.patches[i];
    if (!(glm::dot(p.normal, sun) > 1e-9)) return 0.0;  // facing away or edge-on (sun.hpp)
    if (s.objects[p.object] != "ground") return 1.0;
    return 1.0 - test::box_shadow_on_ground(sun.x, sun.y, sun.z) / 100.0;
}

// Tolerance. The pixel h is set by the default pixel budget (2^27 pixels over the projected
// bounding box: h ≈ 6.3e-4 at 5°, 8.5e-4 at 45°, 1.2e-3 at the zenith; printed). The worst case of
// a pixel count is |ΔA| ≲ P h / 2 for a boundary of length P, so a relative error P h / A_p: for
// the ground at 5° (P ≈ 40 + 25 of its edges and the shadow's, A_p = 100 sin 5° = 8.7) that is
// 65 · 6.3e-4 / 8.7 ≈ 4.7e-3, and for the roof at 5° (P ≈ 2.2, A_p = 0.087) 1.6e-2 (the reported
// bound). The grid is
// turned by the golden angle (sun_buffer.cpp), so that no edge runs along the pixel rows and the
// errors of the crossed pixels cancel instead of adding up: the error per edge is O(h² log(L/h)),
// measured here: mean 1.5e-6, max 1.9e-5 over the 60 fractions. The 1e-3 is asserted, with
// the measured errors printed (mean and max).
TEST(SunBuffer, BoxOnPlaneMatchesTheAnalyticShadow) {
    const Scene s = box_on_plane();
    ASSERT_EQ(s.size(), 6u);
    double sum = 0, worst = 0;
    std::size_t count = 0;
    for (const auto& [az, el] : test::kSunPositions) {
        const auto d = test::sun_from_angles(az, el);
        const Vec3 sun(d[0], d[1], d[2]);
        const SunResult r = sunlit_fractions(s, sun);
        ASSERT_EQ(r.fraction.size(), s.size());
        double case_worst = 0;
        for (std::size_t i = 0; i < s.size(); ++i) {
            const double exact = exact_fraction(s, i, r.sun);
            const double err = std::abs(r.fraction[i] - exact);
            EXPECT_LE(err, 1e-3) << "sun " << az << "," << el << " " << s.objects[s.patches[i].object] << ": "
                                 << r.fraction[i] << " vs " << exact;
            EXPECT_GE(r.fraction[i], 0.0);
            EXPECT_LE(r.fraction[i], 1.0);
            sum += err;
            ++count;
            worst = std::max(worst, err);
            case_worst = std::max(case_worst, err);
        }
        std::printf("sun %g,%g: pixel %.3g, %dx%d tiles, ground %.7f (exact %.7f), worst error %.2e, bound %.2e, %zu clamped\n",
                    az, el, r.pixel_size, r.tiles_u, r.tiles_v, r.fraction[0], exact_fraction(s, 0, r.sun), case_worst,
                    r.error_bound, r.clamped);
    }
    std::printf("box on plane, %zu fractions: mean |error| %.2e, max %.2e\n", count, sum / static_cast<double>(count), worst);
}

// Tiles cut the same pixel grid: 256-pixel tiles give the counts of one tile up to the float
// rounding of the vertices' tile coordinates (a pixel where an edge crosses a tile seam at most).
TEST(SunBuffer, TilesCutTheSameGrid) {
    const Scene s = box_on_plane();
    const auto d = test::sun_from_angles(123, 45);
    SunOptions one, many;
    one.max_pixels = many.max_pixels = 1u << 20;
    many.tile = 256;
    const SunResult a = sunlit_fractions(s, Vec3(d[0], d[1], d[2]), one);
    const SunResult b = sunlit_fractions(s, Vec3(d[0], d[1], d[2]), many);
    EXPECT_EQ(a.tiles_u * a.tiles_v, 1);
    EXPECT_GT(b.tiles_u * b.tiles_v, 9);
    EXPECT_EQ(a.pixel_size, b.pixel_size);
    for (std::size_t i = 0; i < s.size(); ++i) {
        const double diff = std::abs(static_cast<double>(a.pixels[i]) - static_cast<double>(b.pixels[i]));
        EXPECT_LE(diff, 8.0) << "patch " << i << ": " << a.pixels[i] << " vs " << b.pixels[i];
    }
}

TEST(SunBuffer, SameInputSameOutput) {
    const Scene s = box_on_plane();
    SunOptions o;
    o.max_pixels = 1u << 22;
    o.tile = 1024;
    const SunResult a = sunlit_fractions(s, Vec3(0.3, -0.5, 0.4), o);
    const SunResult b = sunlit_fractions(s, Vec3(0.3, -0.5, 0.4), o);
    EXPECT_EQ(a.pixels, b.pixels);
    EXPECT_EQ(a.fraction, b.fraction);
}

// One context lent for several suns (a series) gives what a context per call gives. (The calls
// with their own context come first: destroying a context while another is alive can end the EGL
// display they share, so the series makes no other context while it lends one.)
TEST(SunBuffer, ALentContextGivesTheSameCounts) {
    const Scene s = box_on_plane();
    SunOptions o;
    o.max_pixels = 1u << 20;
    const std::vector<Vec3> suns = {Vec3(0.3, -0.5, 0.4), Vec3(-0.7, 0.2, 0.1), Vec3(0.0, 0.0, 1.0)};
    std::vector<SunResult> own;
    for (const Vec3& sun : suns) own.push_back(sunlit_fractions(s, sun, o));
    std::unique_ptr<GlContext> ctx = create_headless_context(o.backend);
    for (std::size_t k = 0; k < suns.size(); ++k) {
        const SunResult b = sunlit_fractions(s, suns[k], o, *ctx);
        EXPECT_EQ(own[k].pixels, b.pixels);
        EXPECT_EQ(own[k].fraction, b.fraction);
    }
}

// A budget far below what the tolerance asks: larger pixels, the bound reported above the
// tolerance, and still every fraction in [0, 1] (the clamp) and near the closed form.
TEST(SunBuffer, PixelBudgetCapsAndReportsTheBound) {
    const Scene s = box_on_plane();
    SunOptions o;
    o.max_pixels = 200 * 200;
    const auto d = test::sun_from_angles(135, 30);
    const SunResult r = sunlit_fractions(s, Vec3(d[0], d[1], d[2]), o);
    EXPECT_LE(r.pixels_u * r.pixels_v, o.max_pixels);
    EXPECT_GT(r.pixel_size, r.wanted_pixel_size);
    EXPECT_GT(r.error_bound, o.tolerance);
    EXPECT_GT(r.under_resolved, 0u);
    for (std::size_t i = 0; i < s.size(); ++i) {
        EXPECT_GE(r.fraction[i], 0.0);
        EXPECT_LE(r.fraction[i], 1.0);
        // Within the worst-case bound the result reports.
        EXPECT_LE(std::abs(r.fraction[i] - exact_fraction(s, i, r.sun)), r.error_bound) << "patch " << i;
    }
}

TEST(SunBuffer, SunBelowTheHorizonLightsNothingFacingUp) {
    const Scene s = box_on_plane();
    const SunResult r = sunlit_fractions(s, Vec3(0, 0, -1));
    for (std::size_t i = 0; i < s.size(); ++i) EXPECT_EQ(r.fraction[i], 0.0) << "patch " << i;
    EXPECT_EQ(r.lit_patches, 0u);
}

TEST(SunBuffer, DirectionsFromAnglesAndRefusals) {
    const Vec3 east = sun_direction_from_angles(90, 0), zenith = sun_direction_from_angles(17, 90),
               north = sun_direction_from_angles(0, 30);
    EXPECT_NEAR(east.x, 1.0, 1e-15);
    EXPECT_NEAR(east.y, 0.0, 1e-15);
    EXPECT_NEAR(zenith.z, 1.0, 1e-15);
    EXPECT_NEAR(north.y, std::cos(M_PI / 6), 1e-15);
    EXPECT_NEAR(north.z, 0.5, 1e-15);
    EXPECT_THROW(sun_direction_from_angles(0, 90.5), InputError);
    EXPECT_THROW(sun_direction_from_angles(NAN, 10), InputError);
    const Scene s = box_on_plane();
    EXPECT_THROW(sunlit_fractions(s, Vec3(0, 0, 0)), InputError);
    EXPECT_THROW(sunlit_fractions(s, Vec3(0, NAN, 1)), InputError);
    SunOptions bad;
    bad.tolerance = 0;
    EXPECT_THROW(sunlit_fractions(s, Vec3(0, 0, 1), bad), InputError);
}

}  // namespace
}  // namespace ffcube
