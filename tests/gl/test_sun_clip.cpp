// Sunlit fractions by shadow polygons (gl/sun.hpp, sunlit_fractions_clipped; sun_clip.cpp): a box
// on a plane and two overlapping floating squares against closed forms, to rounding; a city of
// turned boxes against the item buffer (an independent method: pixel counts on the GL), within
// the pixel counts' own error bound; the same numbers for any thread count.
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

// Rounding: the areas are sums of a few hundred products of coordinates of size ≤ 10 (areas ≤ 100)
// in double (relative 1.1e-16 each): an absolute error far below 1e-12 on a projected area of at
// least 100 sin 5° = 8.7, i.e. ~1e-13 on a fraction. 1e-10 leaves a factor 1000 of margin and is
// still 7 orders below the item buffer's tolerance 1e-3.
constexpr double kRounding = 1e-10;

using test::box_on_plane;

TEST(SunClip, BoxOnPlaneIsExactToRounding) {
    const Scene s = box_on_plane();
    double worst = 0.0;
    for (const auto& [az, el] : test::kSunPositions) {
        const auto d = test::sun_from_angles(az, el);
        const SunResult r = sunlit_fractions_clipped(s, Vec3(d[0], d[1], d[2]));
        ASSERT_EQ(r.fraction.size(), s.size());
        for (std::size_t i = 0; i < s.size(); ++i) {
            const Patch& p = s.patches[i];
            double exact = glm::dot(p.normal, r.sun) > 1e-9 ? 1.0 : 0.0;  // a convex box shades none of its own faces
            if (s.objects[p.object] == "ground") exact = 1.0 - test::box_shadow_on_ground(r.sun.x, r.sun.y, r.sun.z) / 100.0;
            EXPECT_NEAR(r.fraction[i], exact, kRounding) << "sun " << az << "," << el << " " << s.objects[p.object];
            worst = std::max(worst, std::abs(r.fraction[i] - exact));
        }
    }
    std::printf("box on plane, 60 fractions: largest |error| %.2e\n", worst);
}

// Length of the overlap of [a0, a1] and [b0, b1].
double overlap(double a0, double a1, double b0, double b1) { return std::max(0.0, std::min(a1, b1) - std::max(a0, b0)); }

// Two horizontal squares over a ground [−5,5]²: A = [0,2]² at z = 1 facing up, B = [1,3]×[0.5,2.5]
// at z = 2 facing down (its back to the sun: it shades as a front face does). For the sun s the
// shadow of a horizontal rectangle at height z on a plane at height z' < z is the rectangle
// translated by −(z − z')(s_x, s_y)/s_z, so every shaded area is a union of axis-aligned rectangles:
//   ground: 1 − (|A'| + |B'| − |A' ∩ B'|)/100, A', B' the translates to z = 0;
//   A:      1 − |A ∩ B''|/4, B'' the translate of B to z = 1;  B: 0 (it faces away).
TEST(SunClip, OverlappingShadowsAreTheirUnion) {
    const std::vector<NamedPolygon> polys{
        {"ground", {{-5, -5, 0}, {5, -5, 0}, {5, 5, 0}, {-5, 5, 0}}},
        {"A", {{0, 0, 1}, {2, 0, 1}, {2, 2, 1}, {0, 2, 1}}},
        {"B", {{1, 0.5, 2}, {1, 2.5, 2}, {3, 2.5, 2}, {3, 0.5, 2}}},
    };
    const Scene s = test::make_scene(polys, 100.0);
    ASSERT_EQ(s.size(), 3u);
    for (const Vec3 sun : {Vec3(0.3, 0.2, 1.0), Vec3(-0.25, 0.1, 0.8), Vec3(0.05, -0.4, 0.9), Vec3(0, 0, 1)}) {
        const Vec3 u = glm::normalize(sun);
        const double tx = u.x / u.z, ty = u.y / u.z;  // shift per unit of height
        const double ax0 = 0 - tx, ax1 = 2 - tx, ay0 = 0 - ty, ay1 = 2 - ty;              // A at z = 0
        const double bx0 = 1 - 2 * tx, bx1 = 3 - 2 * tx, by0 = 0.5 - 2 * ty, by1 = 2.5 - 2 * ty;  // B at z = 0
        const double ground = 1.0 - (4.0 + 4.0 - overlap(ax0, ax1, bx0, bx1) * overlap(ay0, ay1, by0, by1)) / 100.0;
        const double a = 1.0 - overlap(0, 2, 1 - tx, 3 - tx) * overlap(0, 2, 0.5 - ty, 2.5 - ty) / 4.0;  // B at z = 1
        const SunResult r = sunlit_fractions_clipped(s, sun);
        EXPECT_NEAR(r.fraction[0], ground, kRounding) << sun.x << "," << sun.y << "," << sun.z;
        EXPECT_NEAR(r.fraction[1], a, kRounding) << sun.x << "," << sun.y << "," << sun.z;
        EXPECT_EQ(r.fraction[2], 0.0);
    }
}

// Boxes turned by various angles (edges at every slope), of various heights, on a ground meshed
// into 2-unit patches; walls and roofs meshed too. Deterministic.
Scene city_of_turned_boxes() {
    std::vector<NamedPolygon> polys{{"ground", {{-12, -12, 0}, {12, -12, 0}, {12, 12, 0}, {-12, 12, 0}}}};
    int k = 0;
    for (int gx = -1; gx <= 1; ++gx)
        for (int gy = -1; gy <= 1; ++gy, ++k) {
            const double a = 0.37 * k + 0.1, c = std::cos(a), sn = std::sin(a);
            const double hx = 1.5 + 0.3 * (k % 3), hy = 1.0 + 0.25 * (k % 4), h = 1.5 + 0.7 * ((k * 5) % 7);
            const Vec3 o(7.0 * gx, 7.0 * gy, 0.0);
            const auto at = [&](double x, double y, double z) { return o + Vec3(c * x - sn * y, sn * x + c * y, z); };
            const std::string name = "b" + std::to_string(k);
            polys.push_back({name, {at(-hx, -hy, h), at(hx, -hy, h), at(hx, hy, h), at(-hx, hy, h)}});
            const Vec3 q[4] = {at(-hx, -hy, 0), at(hx, -hy, 0), at(hx, hy, 0), at(-hx, hy, 0)};
            for (int e = 0; e < 4; ++e) {
                const Vec3 p0 = q[e], p1 = q[(e + 1) % 4];
                polys.push_back({name, {p0, p1, p1 + Vec3(0, 0, h), p0 + Vec3(0, 0, h)}});
            }
        }
    return test::make_scene(polys, 2.0);
}

// Against the item buffer. Each pixel whose centre's side of some projected edge differs from the
// side most of its square lies on is counted for the wrong patch, and only pixels crossed by an
// edge can be: a segment of length L crosses at most √2 L / h + 2 pixels of side h. A miscounted
// pixel takes h² from one patch and gives it to another, so
//     Σ_i |A_p,i (f_pixels,i − f_exact,i)| ≤ 2 h² Σ_edges (√2 L_e / h + 2)
// over the edges of every drawn triangle (the vertices' snapping to 1/256 pixel moves an edge by
// at most h/256, inside that count's +2). The clamp to 1 only brings a pixel fraction nearer.
TEST(SunClip, AgreesWithTheItemBufferOnACityOfTurnedBoxes) {
    const Scene s = city_of_turned_boxes();
    ASSERT_GT(s.size(), 200u);
    SunOptions o;
    o.max_pixels = 1u << 22;
    for (const Vec3 sun : {Vec3(0.6, -0.3, 0.5), Vec3(-0.2, -0.9, 0.25), Vec3(0.1, 0.2, 1.0)}) {
        const SunResult exact = sunlit_fractions_clipped(s, sun);
        const SunResult pix = sunlit_fractions(s, sun, o);
        const double h = pix.pixel_size;
        double edges = 0.0;  // Σ_e (√2 L_e / h + 2), L_e projected
        for (const Patch& p : s.patches)
            for (std::uint32_t t = 0; t + 2 < p.count; ++t) {
                const std::uint32_t c[3] = {p.v[0], p.v[t + 1], p.v[t + 2]};
                for (int e = 0; e < 3; ++e) {
                    const Vec3 d = s.positions[c[(e + 1) % 3]] - s.positions[c[e]];
                    const Vec3 dp = d - glm::dot(d, exact.sun) * exact.sun;
                    edges += std::sqrt(2.0) * std::sqrt(glm::dot(dp, dp)) / h + 2.0;
                }
            }
        double total = 0.0, worst = 0.0, sum = 0.0;
        std::size_t lit = 0;
        for (std::size_t i = 0; i < s.size(); ++i) {
            EXPECT_EQ(exact.cosine[i], pix.cosine[i]);
            EXPECT_GE(exact.fraction[i], 0.0);
            EXPECT_LE(exact.fraction[i], 1.0);
            if (!(exact.cosine[i] > 1e-9)) {
                EXPECT_EQ(exact.fraction[i], 0.0);
                continue;
            }
            const double d = std::abs(exact.fraction[i] - pix.fraction[i]);
            total += s.patches[i].area * exact.cosine[i] * d;
            worst = std::max(worst, d);
            sum += d;
            ++lit;
        }
        const double bound = 2.0 * h * h * edges;
        EXPECT_LE(total, bound) << "sun " << sun.x << "," << sun.y << "," << sun.z;
        std::printf("sun %.2f,%.2f,%.2f: %zu lit patches, pixel %.3g: |f_pixels - f_exact| mean %.2e, max %.2e; "
                    "sum of |area| differences %.3g (bound %.3g)\n",
                    sun.x, sun.y, sun.z, lit, h, sum / static_cast<double>(lit), worst, total, bound);
    }
}

TEST(SunClip, SameNumbersForAnyThreadCount) {
    const Scene s = city_of_turned_boxes();
    const Vec3 sun(-0.45, 0.3, 0.35);
    const SunResult one = sunlit_fractions_clipped(s, sun, 1);
    for (const unsigned t : {2u, 3u, 8u}) {
        const SunResult r = sunlit_fractions_clipped(s, sun, t);
        EXPECT_EQ(r.fraction, one.fraction) << t << " threads";
    }
    EXPECT_THROW(sunlit_fractions_clipped(s, Vec3(0, 0, 0)), InputError);
}

}  // namespace
}  // namespace ffcube
