// Hemicube rows against analytic form factors, and the engine's guarantees (precision,
// determinism, culling, one-sidedness). Everything runs on Mesa's llvmpipe: no GPU needed.
//
// How tolerances are derived (used by every comparison below):
//  * Meshing: the hemicube measures the point-to-area factor from each sender patch's centre,
//    so an object-to-object value is the midpoint rule over the sender's patches. That
//    reference is computed exactly here: Σ_i A_i F(c_i → receiver) / Σ_i A_i with Lambert's
//    contour formula (geometry/analytic). Its distance to the closed form is the meshing error,
//    added to the tolerance when comparing with the closed form.
//  * Pixels: σ of each object value from the actual item buffers (support/pixel_sigma.hpp: cut
//    pixels count wholly or not at all, error uniform in ±ΔF/2). The tolerance is 6σ (a false
//    failure about once in 5e8 under the model).
#include <gtest/gtest.h>
#include <sys/socket.h>
#include <unistd.h>

#include <algorithm>

#include <array>
#include <bit>
#include <cmath>
#include <cstdint>
#include <map>
#include <memory>
#include <numbers>
#include <string>
#include <vector>

#include "ffcube/reference/closed_forms.hpp"
#include "ffcube/core/error.hpp"
#include "ffcube/formfactor/checks.hpp"
#include "ffcube/geometry/analytic.hpp"
#include "ffcube/gl/hemicube_provider.hpp"
#include "ffcube/hemicube/layout.hpp"
#include "support/pixel_sigma.hpp"
#include "support/scenes.hpp"

namespace ffcube {
namespace {

using test::NamedPolygon;

struct Result {
    Scene scene;
    CsrMatrix F;
    std::vector<std::vector<double>> G;      // object-to-object F
    std::vector<std::vector<double>> sigma;  // per object pair, pixel discretisation σ (see top)
};

HemicubeOptions options(int resolution, unsigned threads = 2, Backend backend = Backend::Auto) {
    HemicubeOptions o;
    o.resolution = resolution;
    o.threads = threads;
    o.backend = backend;
    return o;
}

Result run(const std::vector<NamedPolygon>& polys, double edge, const HemicubeOptions& opt, bool with_sigma = true) {
    Result r{test::make_scene(polys, edge), {}, {}, {}};
    HemicubeRowProvider provider(r.scene, opt);
    r.F = compute_all_rows(provider);
    r.G = object_form_factors(r.F, r.scene);
    if (with_sigma) r.sigma = test::pixel_sigma(provider, r.scene, opt.resolution);
    return r;
}

// A closed scene seen by hemicubes at resolution n: every row sums to 1 up to float storage of
// its entries (2^-24 relative each: ≤ 6e-8), and no pixel saw nothing or a back face (one such
// pixel costs ≥ 1/(π n²)·(1/3)² of a row, far above that).
void expect_closed_and_watertight(const Scene& scene, int n, const std::string& label) {
    HemicubeRowProvider provider(scene, options(n));
    const CsrMatrix F = compute_all_rows(provider);
    for (std::uint32_t i = 0; i < scene.size(); ++i) EXPECT_NEAR(F.row(i).sum(), 1.0, 1e-7) << "row " << i << " " << label;
    EXPECT_EQ(provider.stats().miss_weight(), 0.0) << label;
    EXPECT_EQ(provider.stats().back_face_weight(), 0.0) << label;
}

std::size_t object_index(const Scene& s, const std::string& name) {
    for (std::size_t k = 0; k < s.objects.size(); ++k)
        if (s.objects[k] == name) return k;
    ADD_FAILURE() << "no object " << name;
    return 0;
}

// Midpoint rule over the sender's patches with exact point-to-polygon values (unoccluded).
double midpoint_reference(const Scene& s, std::size_t a, const std::vector<NamedPolygon>& polys, const std::string& receiver) {
    double num = 0, den = 0;
    for (const Patch& p : s.patches) {
        if (p.object != a) continue;
        double f = 0;
        for (const NamedPolygon& poly : polys)
            if (poly.object == receiver) f += ff_point_polygon(p.centroid, p.normal, poly.vertices);
        num += p.area * f;
        den += p.area;
    }
    return num / den;
}

// Checks G[a][b] against the midpoint reference (pixel tolerance) and the closed form
// (pixel tolerance + meshing error).
void expect_pair(const Result& r, const std::vector<NamedPolygon>& polys, const std::string& from, const std::string& to,
                 double exact) {
    const std::size_t a = object_index(r.scene, from), b = object_index(r.scene, to);
    const double hc = r.G[a][b];
    const double mid = midpoint_reference(r.scene, a, polys, to);
    const double tol = 6.0 * r.sigma[a][b] + 1e-9;
    EXPECT_NEAR(hc, mid, tol) << from << "->" << to << " σ=" << r.sigma[a][b];
    EXPECT_NEAR(hc, exact, tol + std::abs(mid - exact)) << from << "->" << to << " midpoint " << mid;
}

TEST(HemicubeRows, OpposedParallelUnitSquares) {
    const std::vector<NamedPolygon> polys = {test::square_z("a", 0.0, true), test::square_z("b", 1.0, false)};
    const Result r = run(polys, 0.125, options(128));
    const double exact = ff_parallel_rectangles(1, 1, 1);
    EXPECT_NEAR(exact, 0.19982, 5e-6);  // Howell C-11, as tabulated (5 digits)
    expect_pair(r, polys, "a", "b", exact);
    expect_pair(r, polys, "b", "a", exact);
}

TEST(HemicubeRows, PerpendicularSquaresSharingAnEdge) {
    // Floor [0,1]² facing +z; wall in the plane x = 0, y,z ∈ [0,1], facing +x.
    const std::vector<NamedPolygon> polys = {
        test::square_z("floor", 0.0, true),
        {"wall", {Vec3(0, 0, 0), Vec3(0, 1, 0), Vec3(0, 1, 1), Vec3(0, 0, 1)}}};
    const Result r = run(polys, 0.125, options(128));
    const double exact = ff_perpendicular_rectangles_common_edge(1, 1, 1);
    EXPECT_NEAR(exact, 0.20004, 5e-6);  // Howell C-14, as tabulated
    expect_pair(r, polys, "floor", "wall", exact);
    expect_pair(r, polys, "wall", "floor", exact);
}

TEST(HemicubeRows, CoaxialParallelDisks) {
    // Disks of radius 1 at distance 1, as 64-gons. The closed form is for true disks; the
    // 64-gon's exact value comes from the polygon-to-polygon contour integral, and the gap between
    // the two is the polygonisation error, not the hemicube's.
    const int k = 64;
    NamedPolygon lower{"lower", {}}, upper{"upper", {}};
    for (int i = 0; i < k; ++i) {
        const double t = 2 * std::numbers::pi * i / k;
        lower.vertices.emplace_back(std::cos(t), std::sin(t), 0.0);
        upper.vertices.emplace_back(std::cos(-t), std::sin(-t), 1.0);
    }
    const std::vector<NamedPolygon> polys = {lower, upper};
    const Result r = run(polys, 0.25, options(128));
    const double exact_polygons = ff_polygon_polygon(lower.vertices, upper.vertices);
    // Inscribed 64-gons: F changes by less than the relative area deficit 1 − sin(2π/64)·64/(2π) ≈ 1.6e-3.
    const double deficit = 1 - std::sin(2 * std::numbers::pi / k) * k / (2 * std::numbers::pi);
    EXPECT_NEAR(exact_polygons, ff_coaxial_disks(1, 1, 1), 2 * deficit * ff_coaxial_disks(1, 1, 1));
    expect_pair(r, polys, "lower", "upper", exact_polygons);
    expect_pair(r, polys, "upper", "lower", exact_polygons);
}

TEST(HemicubeRows, ClosedCubeAllThirtyPairsAndRowSums) {
    const auto polys = test::inward_box(1, 1, 1);
    const Result r = run(polys, 1.0 / 6.0, options(128));
    const double opposite = ff_parallel_rectangles(1, 1, 1);
    const double adjacent = ff_perpendicular_rectangles_common_edge(1, 1, 1);
    EXPECT_NEAR(opposite + 4 * adjacent, 1.0, 1e-9);  // the closed forms close the cube
    int pairs = 0;
    for (const auto& a : polys)
        for (const auto& b : polys) {
            if (a.object == b.object) continue;
            const bool opp = a.object[0] == b.object[0];  // x0/x1, y0/y1, z0/z1
            expect_pair(r, polys, a.object, b.object, opp ? opposite : adjacent);
            ++pairs;
        }
    EXPECT_EQ(pairs, 30);
    // Closed enclosure: every pixel sees a wall, so each row sums to Σ ΔF = 1. Entries are stored
    // as float (relative error ≤ 2^-24 each), so the sum is off by at most 6e-8.
    const RowSumStats rs = row_sum_stats(r.F);
    EXPECT_NEAR(rs.min, 1.0, 1e-7);
    EXPECT_NEAR(rs.max, 1.0, 1e-7);
}

TEST(HemicubeRows, NeverSelfNorBehindThePlane) {
    const auto polys = test::inward_box(1, 2, 0.5);
    const Result r = run(polys, 0.25, options(64), false);
    for (std::uint32_t i = 0; i < r.scene.size(); ++i) {
        const Patch& p = r.scene.patches[i];
        const RowView row = r.F.row(i);
        for (std::uint32_t j : row.col) {
            EXPECT_NE(j, i);
            // Patches of the same wall are coplanar: never seen. Others lie in front.
            EXPECT_NE(r.scene.patches[j].object, p.object);
        }
    }
}

// The same scene moved far away or scaled gives the same object-to-object factors.
TEST(HemicubeRows, TranslationAndScaleInvariance) {
    auto scene_at = [](double scale, Vec3 offset) {
        std::vector<NamedPolygon> polys = {
            test::square_z("a", 0.0, true), test::square_z("b", 1.0, false),
            {"wall", {Vec3(0, 0, 0), Vec3(0, 1, 0), Vec3(0, 1, 1), Vec3(0, 0, 1)}}};
        for (auto& p : polys)
            for (auto& v : p.vertices) v = v * scale + offset;
        return polys;
    };
    const auto base = run(scene_at(1.0, Vec3(0.0)), 0.25, options(128), false);
    struct Case {
        double scale;
        Vec3 offset;
    };
    for (const Case c : {Case{1.0, Vec3(1e5, -1e5, 1e5)}, Case{1e-4, Vec3(0.0)}, Case{1e4, Vec3(0.0)},
                         Case{1e-4, Vec3(3.0, 0, 0)}}) {
        const auto moved = run(scene_at(c.scale, c.offset), 0.25 * c.scale, options(128), false);
        ASSERT_EQ(moved.scene.size(), base.scene.size());
        for (std::size_t a = 0; a < base.G.size(); ++a)
            for (std::size_t b = 0; b < base.G.size(); ++b)
                EXPECT_NEAR(moved.G[a][b], base.G[a][b], 1e-4 * base.G[a][b])
                    << "scale " << c.scale << " offset " << c.offset.x << " pair " << a << "," << b;
    }
}

// Depth: two parallel layers 1e-4 of the scene size apart; the nearer hides the farther fully.
TEST(HemicubeRows, DepthResolvesLayersOneTenThousandthApart) {
    for (const Vec3 offset : {Vec3(0.0), Vec3(1e5, 1e5, -1e5)}) {
        const std::vector<NamedPolygon> polys = {test::square_z("sender", 0.0, true, 1.0, offset),
                                                 test::square_z("near", 1.0, false, 1.0, offset),
                                                 test::square_z("far", 1.0 + 1e-4, false, 1.0, offset)};
        const Result r = run(polys, 0.25, options(128), false);
        const std::size_t s = object_index(r.scene, "sender"), n = object_index(r.scene, "near"),
                          f = object_index(r.scene, "far");
        EXPECT_EQ(r.G[s][f], 0.0);
        EXPECT_NEAR(r.G[s][n], ff_parallel_rectangles(1, 1, 1), 0.01);
    }
}

// Faces are one-sided: a back face blocks but receives nothing.
TEST(HemicubeRows, BackFacesBlockAndReceiveNothing) {
    const std::vector<NamedPolygon> polys = {test::square_z("sender", 0.0, true),
                                             test::square_z("backwards", 0.5, true, 1.0),  // faces away from sender
                                             test::square_z("hidden", 1.0, false)};
    HemicubeOptions o = options(64);
    const Scene scene = test::make_scene(polys, 0.5);
    HemicubeRowProvider provider(scene, o);
    const CsrMatrix F = compute_all_rows(provider);
    const auto G = object_form_factors(F, scene);
    const std::size_t s = object_index(scene, "sender"), bw = object_index(scene, "backwards"),
                      h = object_index(scene, "hidden");
    EXPECT_EQ(G[s][bw], 0.0);
    EXPECT_EQ(G[s][h], 0.0);
    EXPECT_GT(provider.stats().back_face_weight(), 0.0);
    // 'backwards' faces up, toward 'hidden' (which faces down): they see each other.
    EXPECT_GT(G[bw][h], 0.1);
}

// A two-sided plate made of two one-sided faces back to back in one plane, inside a closed box:
// each side must show its own front (no z-fighting with the other face's back, which would be
// absorbed and drop row sums), and nothing may leak through. Rows of a closed scene sum to 1
// up to float accumulation (5,000-odd ΔF terms of ~1e-5 each in double: ~1e-12; the ΔF table
// itself sums to 1 within 1e-13) plus float storage of the entries (2^-24 relative each: ≤ 6e-8 on the
// sum); a pixel lost to the wrong side costs ΔF ≥ 1/(π N²)·(1/3)^2 ≈
// 8.6e-6 at N = 64 (a corner pixel of a side face), so 1e-7 separates the two cleanly.
TEST(HemicubeRows, TwoSidedPlateShowsBothFrontsAndLeaksNothing) {
    std::vector<NamedPolygon> polys = test::inward_box(1, 1, 1);
    polys.push_back(test::square_z("plate_up", 0.5, true, 0.5, Vec3(0.25, 0.25, 0)));
    polys.push_back(test::square_z("plate_down", 0.5, false, 0.5, Vec3(0.25, 0.25, 0)));
    // Meshed 8 and 24 per wall: at 24 the wall patches level with the plate see it edge-on from
    // close by, where the two faces' depths differ by more than any small offset (before twin
    // pieces were skipped, rows there summed to 0.99992 at N = 64).
    for (const auto& [n, edge] : {std::pair{32, 0.125}, std::pair{64, 0.125}, std::pair{64, 1.0 / 24}}) {
        const Scene scene = test::make_scene(polys, edge * (1 + 1e-9));
        HemicubeRowProvider provider(scene, options(n));
        const CsrMatrix F = compute_all_rows(provider);
        for (std::uint32_t i = 0; i < scene.size(); ++i) EXPECT_NEAR(F.row(i).sum(), 1.0, 1e-7) << "row " << i << " N=" << n;
        EXPECT_EQ(provider.stats().back_face_weight(), 0.0) << "a back face won a pixel somewhere (N=" << n << ")";
        EXPECT_EQ(provider.stats().miss_weight(), 0.0);
        // The floor sees the plate's lower side, the ceiling its upper side, never the other.
        const auto G = object_form_factors(F, scene);
        const std::size_t up = object_index(scene, "plate_up"), down = object_index(scene, "plate_down"),
                          floor = object_index(scene, "z0"), ceiling = object_index(scene, "z1");
        EXPECT_GT(G[floor][down], 0.1);
        EXPECT_EQ(G[floor][up], 0.0);
        EXPECT_GT(G[ceiling][up], 0.1);
        EXPECT_EQ(G[ceiling][down], 0.0);
    }
}

// T-junctions: a closed box whose floor is three faces meeting at a T (a vertex of two of them
// lies inside an edge of the third) and whose x = 0 wall is two faces split at a height the
// floor's faces do not share. Edges that do not share vertices are rasterized from different
// endpoints; a crack between them would let a pixel see out of the box (miss) or see a back
// face. Rows must sum to 1 as in a box without junctions (bound as above).
TEST(HemicubeRows, TJunctionsLeakNothing) {
    std::vector<NamedPolygon> polys;
    for (const NamedPolygon& p : test::inward_box(1, 1, 1))
        if (p.object != "z0" && p.object != "x0") polys.push_back(p);
    polys.push_back({"floor_a", {{0, 0, 0}, {1, 0, 0}, {1, 0.5, 0}, {0, 0.5, 0}}});
    polys.push_back({"floor_b", {{0, 0.5, 0}, {0.3, 0.5, 0}, {0.3, 1, 0}, {0, 1, 0}}});
    polys.push_back({"floor_c", {{0.3, 0.5, 0}, {1, 0.5, 0}, {1, 1, 0}, {0.3, 1, 0}}});
    polys.push_back({"wall_lo", {{0, 0, 0}, {0, 1, 0}, {0, 1, 0.37}, {0, 0, 0.37}}});
    polys.push_back({"wall_hi", {{0, 0, 0.37}, {0, 1, 0.37}, {0, 1, 1}, {0, 0, 1}}});
    expect_closed_and_watertight(test::make_scene(polys, 0.15), 64, "T-junctions");
}

// T-junctions as OBJ files write them: coordinates with 6 significant digits. A corner that lies
// inside another piece's edge in exact arithmetic is then off that edge by up to half a unit in
// the 6th digit (here 1e-7 of the edge: the ceiling's oblique edge from (0, 0) to (1, 0.7) and a
// corner at (0.333333, 0.233333), where 0.7 × 0.333333 = 0.2333331). Not found as a T-vertex it
// cracked (pixels saw out of the box); the tolerance is 1e-6 of the edge. Rows sum to 1 within
// float storage (bound as above); nothing escapes, no back face shows.
TEST(HemicubeRows, TJunctionsWithSixDigitCoordinatesLeakNothing) {
    std::vector<NamedPolygon> polys;
    for (const NamedPolygon& p : test::inward_box(1, 1, 1))
        if (p.object != "z1") polys.push_back(p);
    // The ceiling, facing down (clockwise seen from above): a triangle under the oblique edge,
    // and the rest in two pieces meeting at a corner on that edge.
    const Vec3 t(0.333333, 0.233333, 1);
    polys.push_back({"ceil_a", {{0, 0, 1}, {1, 0, 1}, {1, 0.7, 1}}});
    polys.push_back({"ceil_b", {{0, 0, 1}, t, {0, 1, 1}}});
    polys.push_back({"ceil_c", {t, {1, 0.7, 1}, {1, 1, 1}, {0, 1, 1}}});
    for (auto& p : polys)
        if (p.object.rfind("ceil", 0) == 0) std::reverse(p.vertices.begin(), p.vertices.end());
    for (const double edge : {2.0, 0.15}) expect_closed_and_watertight(test::make_scene(polys, edge), 64, "six digits");
}

// T-junctions in every arrangement: a floor piece with T-vertices inside all four edges, ceiling
// triangles with T-vertices on one edge and on two, and brick-bonded walls where every brick has
// T-vertices on two opposite edges (and the walls beside them many along their shared edge).
// Near the origin and 1e5 away (the tolerance that finds T-vertices grows with the
// coordinates). Bound as above.
TEST(HemicubeRows, TJunctionsOnEveryEdgeTrianglesAndBricksLeakNothing) {
    std::vector<NamedPolygon> polys;
    for (const NamedPolygon& p : test::inward_box(1, 1, 1))
        if (p.object == "x1" || p.object == "y1") polys.push_back(p);
    // Floor: the square [0.25, 0.75]² in the middle, and strips around it split at x or y = 0.5, so
    // the middle square has a T-vertex inside each edge and each strip one inside its inner edge.
    const auto floor_rect = [&](const std::string& name, double x0, double y0, double x1, double y1) {
        polys.push_back({name, {{x0, y0, 0}, {x1, y0, 0}, {x1, y1, 0}, {x0, y1, 0}}});
    };
    floor_rect("floor_mid", 0.25, 0.25, 0.75, 0.75);
    floor_rect("floor_s0", 0, 0, 0.5, 0.25);
    floor_rect("floor_s1", 0.5, 0, 1, 0.25);
    floor_rect("floor_n0", 0, 0.75, 0.5, 1);
    floor_rect("floor_n1", 0.5, 0.75, 1, 1);
    floor_rect("floor_w0", 0, 0.25, 0.25, 0.5);
    floor_rect("floor_w1", 0, 0.5, 0.25, 0.75);
    floor_rect("floor_e0", 0.75, 0.25, 1, 0.5);
    floor_rect("floor_e1", 0.75, 0.5, 1, 0.75);
    // Ceiling (facing down): one triangle, and the other half split at the diagonal's midpoint.
    polys.push_back({"ceil_a", {{0, 0, 1}, {0, 1, 1}, {1, 1, 1}}});
    polys.push_back({"ceil_b", {{0, 0, 1}, {0.5, 0.5, 1}, {1, 0, 1}}});
    polys.push_back({"ceil_c", {{0.5, 0.5, 1}, {1, 1, 1}, {1, 0, 1}}});
    // Walls x = 0 (facing +x) and y = 0 (facing +y) in brick bond: courses of height 1/5, bricks of
    // width 1/3, every other course shifted by half a brick.
    for (int c = 0; c < 5; ++c) {
        const double z0 = c / 5.0, z1 = (c + 1) / 5.0, shift = c % 2 ? 1.0 / 6.0 : 0.0;
        std::vector<double> cuts = {0.0};
        for (double a = shift > 0 ? shift : 1.0 / 3.0; a < 1 - 1e-9; a += 1.0 / 3.0) cuts.push_back(a);
        cuts.push_back(1.0);
        for (std::size_t b = 0; b + 1 < cuts.size(); ++b) {
            const double a0 = cuts[b], a1 = cuts[b + 1];
            const std::string id = std::to_string(c) + "_" + std::to_string(b);
            polys.push_back({"x0_" + id, {{0, a0, z0}, {0, a1, z0}, {0, a1, z1}, {0, a0, z1}}});
            polys.push_back({"y0_" + id, {{a0, 0, z0}, {a0, 0, z1}, {a1, 0, z1}, {a1, 0, z0}}});
        }
    }
    for (const Vec3 offset : {Vec3(0.0), Vec3(1e5, -1e5, 1e5)}) {
        std::vector<NamedPolygon> moved = polys;
        for (auto& p : moved)
            for (auto& v : p.vertices) v += offset;
        const Scene scene = test::make_scene(moved, 0.2);
        expect_closed_and_watertight(scene, 64, "offset " + std::to_string(offset.x));
    }
}

// The walls of the box [0,1]³ as frames: o + a u + b v for a, b ∈ [0, 1], u × v the inward normal.
struct WallFrame {
    Vec3 o, u, v;
};
constexpr WallFrame kInwardWalls[6] = {{{0, 0, 0}, {1, 0, 0}, {0, 1, 0}}, {{0, 0, 1}, {0, 1, 0}, {1, 0, 0}},
                                       {{0, 0, 0}, {0, 1, 0}, {0, 0, 1}}, {{1, 0, 0}, {0, 0, 1}, {0, 1, 0}},
                                       {{0, 0, 0}, {0, 0, 1}, {1, 0, 0}}, {{0, 1, 0}, {1, 0, 0}, {0, 0, 1}}};

// Arbitrary T-junctions: each wall of a closed box is cut at random (guillotine cuts at eighths
// of the part being cut, so corners often fall inside other parts' edges, sometimes on their
// corners), and some parts are drawn as two triangles or as three (one split at the midpoint of
// the diagonal). The generator is spelled out so the scene is the same everywhere.
TEST(HemicubeRows, RandomTJunctionLayoutsLeakNothing) {
    std::uint64_t state = 0x2545F4914F6CDD1Dull;
    const auto uniform = [&state] {  // splitmix64, to [0, 1)
        std::uint64_t z = (state += 0x9E3779B97F4A7C15ull);
        z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
        z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
        return static_cast<double>((z ^ (z >> 31)) >> 11) * 0x1.0p-53;
    };
    for (const Vec3 offset : {Vec3(0.0), Vec3(1e5, -3e4, 7e4)}) {
        std::vector<NamedPolygon> polys;
        for (int w = 0; w < 6; ++w) {
            const WallFrame& f = kInwardWalls[w];
            const auto at = [&](double a, double b) { return f.o + f.u * a + f.v * b + offset; };
            std::vector<std::array<double, 4>> todo = {{0, 0, 1, 1}};  // a0, b0, a1, b1
            while (!todo.empty()) {
                const auto r = todo.back();
                todo.pop_back();
                const double da = r[2] - r[0], db = r[3] - r[1];
                if (da < 0.2 && db < 0.2) {
                    const std::string name = "w" + std::to_string(w);
                    const double kind = uniform();
                    const Vec3 p00 = at(r[0], r[1]), p10 = at(r[2], r[1]), p11 = at(r[2], r[3]), p01 = at(r[0], r[3]);
                    if (kind < 0.6) {
                        polys.push_back({name, {p00, p10, p11, p01}});
                    } else if (kind < 0.8) {
                        polys.push_back({name, {p00, p10, p11}});
                        polys.push_back({name, {p00, p11, p01}});
                    } else {
                        const Vec3 mid = at(0.5 * (r[0] + r[2]), 0.5 * (r[1] + r[3]));
                        polys.push_back({name, {p00, p10, p11}});
                        polys.push_back({name, {p00, mid, p01}});
                        polys.push_back({name, {mid, p11, p01}});
                    }
                    continue;
                }
                const double cut = std::round((0.2 + 0.6 * uniform()) * 8) / 8;
                if (da >= db) {
                    const double a = r[0] + da * cut;
                    todo.push_back({r[0], r[1], a, r[3]});
                    todo.push_back({a, r[1], r[2], r[3]});
                } else {
                    const double b = r[1] + db * cut;
                    todo.push_back({r[0], r[1], r[2], b});
                    todo.push_back({r[0], b, r[2], r[3]});
                }
            }
        }
        const Scene scene = test::make_scene(polys, 0.15);
        expect_closed_and_watertight(scene, 64, "offset " + std::to_string(offset.x));
    }
}

// Many small pieces: a closed box of 24,000 bricks (50 courses of 80, brick bond), T-vertices on
// almost every brick. From most eyes, bricks far along a wall are slivers far thinner than the
// rasterizer's subpixel grid, which snapping can turn over: such a triangle must still show its
// piece's front (the pass decides the side, not gl_FrontFacing, which gave back-face pixels here).
TEST(HemicubeRows, ManyBricksShowNoBackFacesAndLeakNothing) {
    std::vector<NamedPolygon> polys;
    const int courses = 50, bricks = 80;
    for (const WallFrame& f : kInwardWalls)
        for (int c = 0; c < courses; ++c) {
            const double b0 = double(c) / courses, b1 = double(c + 1) / courses;
            std::vector<double> cuts = {0.0};
            for (int k = 1; k <= bricks; ++k) {
                const double a = (k - (c % 2 ? 0.5 : 0.0)) / bricks;
                if (a < 1) cuts.push_back(a);
            }
            cuts.push_back(1.0);
            for (std::size_t k = 0; k + 1 < cuts.size(); ++k) {
                const double a0 = cuts[k], a1 = cuts[k + 1];
                polys.push_back({"bricks", {f.o + f.u * a0 + f.v * b0, f.o + f.u * a1 + f.v * b0,
                                            f.o + f.u * a1 + f.v * b1, f.o + f.u * a0 + f.v * b1}});
            }
        }
    const Scene scene = test::make_scene(polys, 1.0);  // one patch per brick
    HemicubeRowProvider provider(scene, options(64));
    std::vector<std::uint32_t> rows;
    for (std::size_t k = 0; k < 20; ++k) rows.push_back(static_cast<std::uint32_t>(k * scene.size() / 20));
    provider.compute_rows(rows, [](std::uint32_t i, const SparseRow& row) {
        double sum = 0;
        for (const double v : row.val) sum += v;
        EXPECT_NEAR(sum, 1.0, 1e-7) << "row " << i;
    });
    EXPECT_EQ(provider.stats().miss_weight(), 0.0);
    EXPECT_EQ(provider.stats().back_face_weight(), 0.0);
}

// The worker lists a row's columns by sorting the ones it touched (a sparse row: m columns of n
// with m·log2(m) ≤ n) or by one pass over all n columns (a dense row). A 4 × 4 floor in 1,024
// patches under a 0.5 square in 16 facing it: the floor's rows see at most the square's 16 patches
// (sorted), the square's rows most of the floor (the pass). Both kinds must list strictly
// increasing columns, and both objects' factors must match the midpoint reference within the
// pixel tolerance derived at the top (6σ).
TEST(HemicubeRows, SparseAndDenseRowsListIncreasingColumns) {
    const std::vector<NamedPolygon> polys = {test::square_z("floor", 0.0, true, 4.0),
                                             test::square_z("square", 1.0, false, 0.5, Vec3(1.75, 1.75, 0.0))};
    const Result r = run(polys, 0.125, options(64));
    const std::size_t n = r.scene.size();
    ASSERT_EQ(n, 1040u);
    const std::size_t floor = object_index(r.scene, "floor"), square = object_index(r.scene, "square");
    std::size_t sparse = 0, dense = 0;
    for (std::uint32_t i = 0; i < n; ++i) {
        const RowView row = r.F.row(i);
        const std::size_t m = row.col.size();
        (m * static_cast<std::size_t>(std::bit_width(m)) > n ? dense : sparse) += 1;
        for (std::size_t k = 1; k < m; ++k) ASSERT_LT(row.col[k - 1], row.col[k]) << "row " << i;
    }
    EXPECT_EQ(sparse, 1024u);  // the floor's rows (a row's touched columns include zero entries: at most 16)
    EXPECT_EQ(dense, 16u);     // the square's
    for (const auto& [a, b] : {std::pair{floor, square}, std::pair{square, floor}}) {
        const double mid = midpoint_reference(r.scene, a, polys, r.scene.objects[b]);
        EXPECT_NEAR(r.G[a][b], mid, 6.0 * r.sigma[a][b] + 1e-9) << r.scene.objects[a] << "->" << r.scene.objects[b];
    }
}

TEST(HemicubeRows, SameRowsWithOneOrTwoThreads) {
    const auto polys = test::inward_box(1, 1, 2);
    const Result one = run(polys, 0.25, options(64, 1), false);
    const Result two = run(polys, 0.25, options(64, 2), false);
    EXPECT_EQ(one.F.row_ptr(), two.F.row_ptr());
    EXPECT_EQ(one.F.col(), two.F.col());
    EXPECT_EQ(one.F.val(), two.F.val());
}

TEST(HemicubeRows, EglAndOsMesaGiveTheSameRows) {
    const auto polys = test::inward_box(1, 1.5, 1);
    const Result egl = run(polys, 0.25, options(64, 1, Backend::Egl), false);
    const Result osm = run(polys, 0.25, options(64, 1, Backend::OsMesa), false);
    ASSERT_EQ(egl.F.nnz(), osm.F.nnz());
    for (std::uint32_t i = 0; i < egl.F.size(); ++i) {
        const RowView a = egl.F.row(i), b = osm.F.row(i);
        ASSERT_EQ(a.col.size(), b.col.size()) << "row " << i;
        for (std::size_t k = 0; k < a.col.size(); ++k) {
            EXPECT_EQ(a.col[k], b.col[k]);
            EXPECT_NEAR(a.val[k], b.val[k], 1e-6);
        }
    }
}

TEST(HemicubeRows, RotationIsDeterministicAndChangesAliasing) {
    const std::vector<NamedPolygon> polys = {test::square_z("a", 0.0, true), test::square_z("b", 1.0, false)};
    const Result r1 = run(polys, 0.5, options(32), false);
    const Result r2 = run(polys, 0.5, options(32), false);
    EXPECT_EQ(r1.F.val(), r2.F.val());
    HemicubeOptions fixed = options(32);
    fixed.rotate = false;
    const Result r3 = run(polys, 0.5, fixed, false);
    EXPECT_NE(r1.F.val(), r3.F.val());
}

}  // namespace
}  // namespace ffcube

namespace ffcube {
namespace {

// Worker processes (the default while this process has no GL context and one thread) and
// worker threads (the fallback) run the same code on the same rasterizer: identical rows.
TEST(HemicubeWorkers, ProcessesAndThreadsGiveIdenticalRows) {
    const Scene scene = test::make_scene(test::inward_box(1, 2, 1), 0.25);
    HemicubeOptions o;
    o.resolution = 64;
    o.threads = 2;
    CsrMatrix by_processes, by_threads;
    {
        HemicubeRowProvider provider(scene, o);
        EXPECT_EQ(provider.workers(), "processes");
        by_processes = compute_all_rows(provider);
    }
    // A GL context made in this process makes forking unsafe from now on.
    const auto ctx = create_headless_context(Backend::Auto);
    {
        HemicubeRowProvider provider(scene, o);
        EXPECT_EQ(provider.workers(), "threads");
        by_threads = compute_all_rows(provider);
    }
    EXPECT_EQ(by_processes.col(), by_threads.col());
    EXPECT_EQ(by_processes.val(), by_threads.val());
}

// A worker process sends a row's header and arrays in one sendmsg: rows larger than the socket's
// buffer (sent by the kernel in several rounds while the reader drains it) arrive whole and
// unchanged. An inward box of
// 64,000 patches at N = 256 (196,608 pixels): a row sees tens of thousands of patches, 12 bytes
// an entry, beyond the default buffer of a Unix socket (212,992 bytes here; read on a fresh
// socket pair, so the test says so where the default is larger).
TEST(HemicubeWorkers, RowsLargerThanTheSocketBufferArriveWhole) {
    const Scene scene = test::make_scene(test::inward_box(1, 2, 1), 0.0125);
    ASSERT_GT(scene.size(), 60000u);
    HemicubeOptions o;
    o.resolution = 256;
    o.threads = 2;
    const std::vector<std::uint32_t> rows = {0, 7, static_cast<std::uint32_t>(scene.size() / 2),
                                             static_cast<std::uint32_t>(scene.size() - 1)};
    const auto compute = [&](const char* kind) {
        HemicubeRowProvider provider(scene, o);
        EXPECT_EQ(provider.workers(), kind);
        std::vector<SparseRow> out;
        provider.compute_rows(rows, [&](std::uint32_t, const SparseRow& r) { out.push_back(r); });
        return out;
    };
    const std::vector<SparseRow> by_processes = compute("processes");
    int sv[2];
    ASSERT_EQ(::socketpair(AF_UNIX, SOCK_STREAM, 0, sv), 0);
    int sndbuf = 0;
    socklen_t len = sizeof sndbuf;
    ASSERT_EQ(::getsockopt(sv[0], SOL_SOCKET, SO_SNDBUF, &sndbuf, &len), 0);
    ::close(sv[0]);
    ::close(sv[1]);
    const auto ctx = create_headless_context(Backend::Auto);  // no forking from now on
    const std::vector<SparseRow> by_threads = compute("threads");
    ASSERT_EQ(by_processes.size(), rows.size());
    ASSERT_EQ(by_threads.size(), rows.size());
    for (std::size_t k = 0; k < rows.size(); ++k) {
        EXPECT_GT(by_processes[k].nnz() * (sizeof(std::uint32_t) + sizeof(double)), static_cast<std::size_t>(sndbuf))
            << "row " << rows[k];
        EXPECT_EQ(by_processes[k].col, by_threads[k].col) << "row " << rows[k];
        EXPECT_EQ(by_processes[k].val, by_threads[k].val) << "row " << rows[k];
    }
}

// set_scene (adaptive levels keep their workers): a provider started on one scene and sent
// another gives the rows and item buffers of a provider started on that other scene, bit for
// bit, and after being sent the first back, the first's again. The scenes differ in geometry,
// patch count and pieces. Forked workers first, then threads (after this process made a context).
TEST(HemicubeWorkers, SetSceneGivesTheRowsOfAProviderStartedOnThatScene) {
    const Scene a = test::make_scene(test::inward_box(1, 2, 1), 0.25);
    const Scene b = test::make_scene({test::square_z("floor", 0.0, true, 2.0, Vec3(-1, -1, 0)),
                                      test::square_z("occluder", 0.5, true, 0.5, Vec3(-0.25, -0.25, 0)),
                                      test::square_z("light", 1.0, false, 0.5, Vec3(-0.5, -0.25, 0))},
                                     0.25);
    ASSERT_NE(a.size(), b.size());
    HemicubeOptions o;
    o.resolution = 64;
    o.threads = 2;
    std::unique_ptr<GlContext> ctx;
    for (const char* kind : {"processes", "threads"}) {
        if (std::string(kind) == "threads") ctx = create_headless_context(Backend::Auto);  // no forking from now on
        CsrMatrix fresh_b;
        std::vector<std::uint32_t> fresh_ids;
        {
            HemicubeRowProvider provider(b, o);
            EXPECT_EQ(provider.workers(), kind);
            fresh_b = compute_all_rows(provider);
            fresh_ids = provider.item_buffer(3);
        }
        HemicubeRowProvider provider(a, o);
        EXPECT_EQ(provider.workers(), kind);
        const CsrMatrix first_a = compute_all_rows(provider);
        provider.set_scene(b);
        EXPECT_EQ(provider.size(), b.size());
        EXPECT_EQ(provider.stats().hemicubes, 0u);  // the counters start again
        const CsrMatrix sent_b = compute_all_rows(provider);
        EXPECT_EQ(sent_b.row_ptr(), fresh_b.row_ptr()) << kind;
        EXPECT_EQ(sent_b.col(), fresh_b.col()) << kind;
        EXPECT_EQ(sent_b.val(), fresh_b.val()) << kind;
        EXPECT_EQ(provider.item_buffer(3), fresh_ids) << kind;
        provider.set_scene(a);
        const CsrMatrix again_a = compute_all_rows(provider);
        EXPECT_EQ(again_a.col(), first_a.col()) << kind;
        EXPECT_EQ(again_a.val(), first_a.val()) << kind;
    }
}

// A worker that cannot start reports why, through the provider's constructor.
TEST(HemicubeWorkers, BadResolutionIsAnInputError) {
    const Scene scene = test::make_scene(test::inward_box(1, 1, 1), 0.5);
    HemicubeOptions o;
    o.resolution = 7;
    EXPECT_THROW(HemicubeRowProvider(scene, o), InputError);
}

}  // namespace
}  // namespace ffcube
