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

#include <cmath>
#include <map>
#include <numbers>

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
    EXPECT_GT(provider.stats().back_face_weight, 0.0);
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
    for (const int n : {32, 64}) {
        const Scene scene = test::make_scene(polys, 0.125);
        HemicubeRowProvider provider(scene, options(n));
        const CsrMatrix F = compute_all_rows(provider);
        for (std::uint32_t i = 0; i < scene.size(); ++i) EXPECT_NEAR(F.row(i).sum(), 1.0, 1e-7) << "row " << i << " N=" << n;
        EXPECT_EQ(provider.stats().back_face_weight, 0.0) << "a back face won a pixel somewhere (N=" << n << ")";
        EXPECT_EQ(provider.stats().miss_weight, 0.0);
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

// A worker that cannot start reports why, through the provider's constructor.
TEST(HemicubeWorkers, BadResolutionIsAnInputError) {
    const Scene scene = test::make_scene(test::inward_box(1, 1, 1), 0.5);
    HemicubeOptions o;
    o.resolution = 7;
    EXPECT_THROW(HemicubeRowProvider(scene, o), InputError);
}

}  // namespace
}  // namespace ffcube
