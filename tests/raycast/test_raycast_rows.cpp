// Ray-cast rows against closed forms, and the provider's guarantees (closed rows sum to 1,
// one-sided faces, determinism across thread counts, offsets and scales).
//
// Tolerances: the ray caster samples the whole sender patch, so an object-to-object value
// G_ab = Σ_i w_i F̂_ib (w_i = A_i/A_a) is an unbiased estimate of the exact area-to-area factor:
// no meshing error, only statistics. Each F̂_ib is a binomial fraction over N rays, variance
// F_ib(1−F_ib)/N or less (stratification only lowers it), so
//   Var G_ab ≤ Σ w_i² F_ib(1−F_ib)/N ≤ max_i w_i · Σ w_i F_ib(1−F_ib)/N ≤ max_i w_i · G(1−G)/N
// (the last step: x(1−x) is concave, Jensen). Comparisons allow 5σ of that bound (a false
// failure about once in 3.5e6 per comparison under the normal approximation).
#include <gtest/gtest.h>

#include <cmath>
#include <mutex>
#include <map>
#include <set>
#include <string>
#include <thread>
#include <vector>

#include "ffcube/reference/closed_forms.hpp"
#include "ffcube/core/error.hpp"
#include "ffcube/formfactor/checks.hpp"
#include "ffcube/geometry/analytic.hpp"
#include "ffcube/raycast/raycast_provider.hpp"
#include "support/scenes.hpp"

namespace ffcube {
namespace {

using test::NamedPolygon;

std::size_t object_index(const Scene& s, const std::string& name) {
    for (std::size_t k = 0; k < s.objects.size(); ++k)
        if (s.objects[k] == name) return k;
    ADD_FAILURE() << "no object " << name;
    return 0;
}

// 5σ with σ from the bound in the header comment, for sender object a.
double tolerance(const Scene& s, std::size_t a, double exact, std::uint64_t rays) {
    double area = 0.0, wmax = 0.0;
    for (const Patch& p : s.patches)
        if (p.object == a) area += p.area;
    for (const Patch& p : s.patches)
        if (p.object == a) wmax = std::max(wmax, p.area / area);
    return 5.0 * std::sqrt(wmax * exact * (1.0 - exact) / static_cast<double>(rays));
}

RaycastOptions options(std::uint64_t rays, unsigned threads = 2) {
    RaycastOptions o;
    o.rays = rays;
    o.threads = threads;
    return o;
}

std::vector<std::vector<double>> object_ff(const Scene& scene, const RaycastOptions& o) {
    RaycastRowProvider provider(scene, o);
    return object_form_factors(compute_all_rows(provider), scene);
}

TEST(RaycastRows, ParallelSquaresMatchTheClosedForm) {
    const Scene scene = test::make_scene({test::square_z("a", 0.0, true), test::square_z("b", 1.0, false)}, 0.25);
    const std::uint64_t rays = 4000;
    const auto G = object_ff(scene, options(rays));
    const std::size_t a = object_index(scene, "a"), b = object_index(scene, "b");
    const double exact = ff_parallel_rectangles(1, 1, 1);
    EXPECT_NEAR(G[a][b], exact, tolerance(scene, a, exact, rays));
    EXPECT_NEAR(G[b][a], exact, tolerance(scene, b, exact, rays));
    EXPECT_EQ(G[a][a], 0.0);  // a planar object cannot see itself
}

TEST(RaycastRows, PerpendicularSquaresMatchTheClosedForm) {
    const std::vector<NamedPolygon> polys = {
        {"floor", {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}}},  // normal +z
        {"wall", {{0, 0, 0}, {0, 1, 0}, {0, 1, 1}, {0, 0, 1}}},   // x = 0, normal +x
    };
    const Scene scene = test::make_scene(polys, 0.25);
    const std::uint64_t rays = 4000;
    const auto G = object_ff(scene, options(rays));
    const std::size_t f = object_index(scene, "floor"), w = object_index(scene, "wall");
    const double exact = ff_perpendicular_rectangles_common_edge(1, 1, 1);
    EXPECT_NEAR(G[f][w], exact, tolerance(scene, f, exact, rays));
    EXPECT_NEAR(G[w][f], exact, tolerance(scene, w, exact, rays));
}

// Every ray leaving a wall of a closed box hits some wall's front: rows sum to 1 up to the
// rounding of the normalisation (values are hits/N on these parallelogram patches).
TEST(RaycastRows, ClosedBoxRowsSumToOneAndMatchClosedForms) {
    const Scene scene = test::make_scene(test::inward_box(1, 1, 1), 0.25);
    const std::uint64_t rays = 2000;
    RaycastRowProvider provider(scene, options(rays));
    const CsrMatrix F = compute_all_rows(provider);
    for (std::uint32_t i = 0; i < F.size(); ++i) EXPECT_NEAR(F.row(i).sum(), 1.0, 1e-6) << "row " << i;  // float storage
    const auto G = object_form_factors(F, scene);
    const std::size_t z0 = object_index(scene, "z0"), z1 = object_index(scene, "z1"), x0 = object_index(scene, "x0");
    const double opposite = ff_parallel_rectangles(1, 1, 1);
    const double adjacent = ff_perpendicular_rectangles_common_edge(1, 1, 1);
    EXPECT_NEAR(G[z0][z1], opposite, tolerance(scene, z0, opposite, rays));
    EXPECT_NEAR(G[z0][x0], adjacent, tolerance(scene, z0, adjacent, rays));
    EXPECT_EQ(provider.stats().rays_traced >= F.size() * rays, true);
}

// A non-parallelogram quad (trapezoid) is sampled with the bilinear map's Jacobian as weight;
// without it the narrow end would be over-sampled. The weights vary by at most 1.5× here, so the
// binomial σ bound grows by at most √1.5; the tolerance is 5σ × √1.5.
TEST(RaycastRows, TrapezoidSenderIsSampledUniformlyByArea) {
    const std::vector<Vec3> trap = {{0, 0, 0}, {2, 0, 0}, {1.5, 1, 0}, {0.5, 1, 0}};
    const std::vector<Vec3> recv = {{0, 0, 1}, {0, 1, 1}, {2, 1, 1}, {2, 0, 1}};
    const Scene scene = test::make_scene({{"trap", trap}, {"recv", recv}}, 10.0);  // one patch each
    ASSERT_EQ(scene.size(), 2u);
    const std::uint64_t rays = 20000;
    const auto G = object_ff(scene, options(rays));
    const double exact = ff_polygon_polygon(trap, recv);
    EXPECT_NEAR(G[0][1], exact, std::sqrt(1.5) * tolerance(scene, 0, exact, rays));
}

TEST(RaycastRows, BackFacesBlockAndReceiveNothing) {
    const Scene scene = test::make_scene({test::square_z("sender", 0.0, true), test::square_z("backwards", 0.5, true),
                                          test::square_z("hidden", 1.0, false)},
                                         0.5);
    const auto G = object_ff(scene, options(500));
    const std::size_t s = object_index(scene, "sender"), bw = object_index(scene, "backwards"),
                      h = object_index(scene, "hidden");
    EXPECT_EQ(G[s][bw], 0.0);
    EXPECT_EQ(G[s][h], 0.0);
    EXPECT_GT(G[bw][h], 0.1);  // exact: 0.415 (C-11 at distance 0.5)
}

TEST(RaycastRows, SameRowsWithOneOrTwoThreadsAndAnyRowOrder) {
    const Scene scene = test::make_scene(test::inward_box(1, 1, 2), 0.25);
    RaycastRowProvider one(scene, options(300, 1));
    RaycastRowProvider two(scene, options(300, 2));
    const CsrMatrix a = compute_all_rows(one), b = compute_all_rows(two);
    EXPECT_EQ(a.col(), b.col());
    EXPECT_EQ(a.val(), b.val());
    // A row asked for alone is the same row.
    SparseRow r;
    two.compute_row(7, r);
    const RowView v = a.row(7);
    ASSERT_EQ(r.nnz(), v.col.size());
    for (std::size_t k = 0; k < r.nnz(); ++k) EXPECT_EQ(static_cast<float>(r.val[k]), v.val[k]);
}

// The caller's finish (the near-field correction's, in a run) runs on the ray caster's worker
// threads: once per listed row, with that row's position k, on the row as cast, before the sink
// sees it; the sink gets the rows in list order, the same with one thread or two.
TEST(RaycastRows, StagedFinishRunsOnceARowOnTheWorkersInListOrder) {
    const Scene scene = test::make_scene(test::inward_box(1, 1, 2), 0.25);
    std::vector<std::uint32_t> rows(scene.size());
    for (std::uint32_t k = 0; k < rows.size(); ++k) rows[k] = (7 * k + 3) % static_cast<std::uint32_t>(rows.size());
    ASSERT_GT(rows.size(), 20u);
    RaycastRowProvider reference(scene, options(300, 1));
    std::vector<SparseRow> plain(rows.size());
    std::size_t at = 0;
    reference.compute_rows(rows, [&](std::uint32_t i, const SparseRow& r) {
        ASSERT_EQ(i, rows[at]);
        plain[at++] = r;
    });
    for (unsigned threads : {1u, 2u}) {
        RaycastRowProvider provider(scene, options(300, threads));
        std::mutex mutex;
        std::vector<int> finished(rows.size(), 0);
        std::set<std::thread::id> finishers;
        RowProvider::RowStages stages;
        // A finish that depends on k and i (as the contract allows): scales the row by 1/(k + 1)
        // and appends a column n + k, so a row finished with the wrong k or twice shows.
        stages.finish = [&](std::size_t k, std::uint32_t i, SparseRow& row) {
            {
                const std::lock_guard lock(mutex);
                ASSERT_LT(k, rows.size());
                EXPECT_EQ(i, rows[k]);
                ++finished[k];
                finishers.insert(std::this_thread::get_id());
            }
            for (double& v : row.val) v /= static_cast<double>(k + 1);
            row.col.push_back(static_cast<std::uint32_t>(scene.size() + k));
            row.val.push_back(1.0);
        };
        std::size_t k = 0;
        provider.compute_rows_staged(rows, stages, [&](std::uint32_t i, const SparseRow& r) {
            ASSERT_LT(k, rows.size());
            EXPECT_EQ(i, rows[k]);
            ASSERT_EQ(r.nnz(), plain[k].nnz() + 1) << "row " << i;
            for (std::size_t e = 0; e + 1 < r.nnz(); ++e) {
                EXPECT_EQ(r.col[e], plain[k].col[e]);
                EXPECT_EQ(r.val[e], plain[k].val[e] / static_cast<double>(k + 1));
            }
            EXPECT_EQ(r.col.back(), scene.size() + k);
            ++k;
        });
        EXPECT_EQ(k, rows.size());
        for (std::size_t m = 0; m < rows.size(); ++m) EXPECT_EQ(finished[m], 1) << "position " << m;
        // Two workers: the finishes ran off the calling thread (on the workers).
        if (threads == 2) {
            EXPECT_EQ(finishers.count(std::this_thread::get_id()), 0u);
        }
    }
}

// The scene is centred and scaled before Embree's float conversion, so an offset of 1e5 or a
// scale of 1e-4 gives the same rows: same rays in the same relative geometry, equal up to
// float rounding of the hit tests (a handful of rays may flip at patch boundaries).
TEST(RaycastRows, OffsetsAndScalesGiveTheSameFactors) {
    const std::uint64_t rays = 2000;
    const double exact = ff_parallel_rectangles(1, 1, 1);
    for (const auto& [scale, offset] : {std::pair{1.0, 1e5}, std::pair{1e-4, 0.0}, std::pair{1e4, -3e4}}) {
        const Scene scene = test::make_scene(
            {test::square_z("a", 0.0, true, scale, Vec3(offset)), test::square_z("b", scale, false, scale, Vec3(offset))},
            0.25 * scale);
        const auto G = object_ff(scene, options(rays));
        EXPECT_NEAR(G[0][1], exact, tolerance(scene, 0, exact, rays)) << "scale " << scale << " offset " << offset;
    }
}

// K copies of a sender and a receiver within a unit cube, on a square grid 3 units apart: K
// independent rows of the same pair, sender "s<k>", receiver "r<k>". Nothing of another copy
// lies between a sender and its own receiver, so F to it is the pair's alone (rays that reach
// other copies add entries to other columns). The grid keeps the scene's extent small: ray
// origins sit kMinOffset × extent off the sender.
std::vector<NamedPolygon> copies(const std::vector<Vec3>& sender, const std::vector<Vec3>& receiver, int K) {
    std::vector<NamedPolygon> polys;
    for (int k = 0; k < K; ++k) {
        const int side = static_cast<int>(std::ceil(std::sqrt(static_cast<double>(K))));
        const Vec3 d(3.0 * (k % side), 3.0 * (k / side), 0);
        std::vector<Vec3> s = sender, r = receiver;
        for (Vec3& v : s) v += d;
        for (Vec3& v : r) v += d;
        polys.push_back({"s" + std::to_string(k), s});
        polys.push_back({"r" + std::to_string(k), r});
    }
    return polys;
}

// F from copy k's sender to its receiver (copies(): one patch each), for every k.
std::vector<double> copy_factors(const Scene& scene, const CsrMatrix& F, int K) {
    std::map<std::string, std::uint32_t> patch;
    for (std::uint32_t i = 0; i < scene.size(); ++i) patch[scene.objects[scene.patches[i].object]] = i;
    std::vector<double> out(K, 0.0);
    for (int k = 0; k < K; ++k) {
        const RowView r = F.row(patch.at("s" + std::to_string(k)));
        const std::uint32_t j = patch.at("r" + std::to_string(k));
        for (std::size_t e = 0; e < r.col.size(); ++e)
            if (r.col[e] == j) out[k] = r.val[e];
    }
    return out;
}

// Any number of rays is unbiased, not only squares: with 5 rays (a 2 × 2 batch and one ray on
// its own) the floor's factor to a wall along one of its edges, averaged over 4,000 independent
// rows, matches the closed form. Reusing stratum 0 for the fifth ray (the sampler before) would
// weight the quarter of the floor beside the wall 2/5 instead of 1/4: +0.019 here (measured),
// 6.6 σ of the mean. Tolerance 4σ of the mean, σ ≤ √(F(1−F)/5) a row (binomial bound).
TEST(RaycastRows, AnyNumberOfRaysIsUnbiased) {
    const std::vector<Vec3> floor = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}};  // normal +z
    const std::vector<Vec3> wall = {{0, 0, 0}, {0, 1, 0}, {0, 1, 1}, {0, 0, 1}};   // x = 0, normal +x
    const int K = 4000;
    const Scene scene = test::make_scene(copies(floor, wall, K), 10.0);
    ASSERT_EQ(scene.size(), static_cast<std::size_t>(2 * K));
    const std::uint64_t rays = 5;
    RaycastRowProvider provider(scene, options(rays));
    const CsrMatrix F = compute_all_rows(provider);
    double sum = 0;
    for (const double f : copy_factors(scene, F, K)) sum += f;
    const double exact = ff_perpendicular_rectangles_common_edge(1, 1, 1);
    const double sigma_mean = std::sqrt(exact * (1 - exact) / static_cast<double>(rays) / K);
    EXPECT_NEAR(sum / K, exact, 4 * sigma_mean);
}

// The scrambled points are unbiased to far below their own noise: the floor's factor to the wall
// along its edge (0.2000438), over 4,000 rows of 4,096 rays (each row its own scramble), averages
// to the closed form within 4 standard errors of the mean, the standard error measured from the
// rows themselves: the rows' spread is 1.8e-3 (measured), 0.29 of the binomial 6.25e-3, so 4
// standard errors are 1.2e-4, where the binomial bound of the test above would allow 4e-4.
TEST(RaycastRows, ScrambledRowsAreUnbiasedToTheirOwnNoise) {
    const std::vector<Vec3> floor = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}};
    const std::vector<Vec3> wall = {{0, 0, 0}, {0, 1, 0}, {0, 1, 1}, {0, 0, 1}};
    const int K = 4000;
    const Scene scene = test::make_scene(copies(floor, wall, K), 10.0);
    RaycastRowProvider provider(scene, options(4096));
    const CsrMatrix F = compute_all_rows(provider);
    double sum = 0, sq = 0;
    for (const double f : copy_factors(scene, F, K)) sum += f, sq += f * f;
    const double mean = sum / K, sd = std::sqrt(std::max(0.0, sq / K - mean * mean));
    const double exact = ff_perpendicular_rectangles_common_edge(1, 1, 1);
    EXPECT_LT(sd, 0.4 * std::sqrt(exact * (1 - exact) / 4096.0));  // the scrambled net's spread
    EXPECT_NEAR(mean, exact, 4 * sd / std::sqrt(static_cast<double>(K))) << "sd " << sd;
}

// Directions are stratified too. A receiver that every point of the sender sees alike (20 × 20
// at distance 10 above a unit sender: moving the ray's origin across the sender moves its hit
// by 1/20 of the receiver) makes the hit indicator a function of the direction alone, to first
// order: a 2-D indicator with a smooth edge, whose jittered estimate over m² = N cells errs
// only in the O(m) cells its edge crosses, Var ≈ c·m/N² = c·N^−1.5, so the error against the
// binomial σ = √(F(1−F)/N) of independent directions is ≈ √(c/(F(1−F)))·N^−1/4: 0.125 × that
// factor at N = 4,096. Asserted: RMS over 400 rows below σ/2 (the RMS of 400 rows is itself
// within ±7% at 2σ). Measured: 0.22 σ with the padded strata, 0.98 σ with independent directions.
TEST(RaycastRows, DirectionsAreStratified) {
    const std::vector<Vec3> a = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}};              // normal +z
    const std::vector<Vec3> b = {{-9.5, -9.5, 10}, {-9.5, 10.5, 10}, {10.5, 10.5, 10}, {10.5, -9.5, 10}};  // normal −z
    const int K = 400;
    std::vector<NamedPolygon> polys;
    for (int k = 0; k < K; ++k) {  // side by side, 30 units apart (farther than the receiver reaches)
        const Vec3 d(30.0 * (k % 20), 30.0 * (k / 20), 0);
        std::vector<Vec3> s = a, r = b;
        for (Vec3& v : s) v += d;
        for (Vec3& v : r) v += d;
        polys.push_back({"s" + std::to_string(k), s});
        polys.push_back({"r" + std::to_string(k), r});
    }
    const Scene scene = test::make_scene(polys, 100.0);
    const std::uint64_t rays = 4096;
    RaycastRowProvider provider(scene, options(rays));
    const CsrMatrix F = compute_all_rows(provider);
    const double exact = ff_polygon_polygon(a, b);
    double sq = 0;
    for (const double f : copy_factors(scene, F, K)) sq += (f - exact) * (f - exact);
    const double rms = std::sqrt(sq / K);
    const double binomial = std::sqrt(exact * (1 - exact) / static_cast<double>(rays));
    EXPECT_LT(rms, 0.5 * binomial);
}

// A two-sided plate (two one-sided faces back to back, the same corners) in a closed box: a ray
// that Embree reports on the back of one face (the two triangles coincide, either may win) is
// counted on its twin's front, as the hemicube shows it. Every ray then lands on a front face, so
// each row sums to 1 exactly (weight 1 a ray: integer counts over R in double), up to rays that a
// float-rounding hit on their own patch's plane made the caster drop (kRetraces): a few in 1e4
// at most, 1e-4 on a sum, while one absorbed ray in 4,096 is 2.4e-4. Before: ceiling rows summed
// to 0.76 to 0.95 (the back face absorbed them). The floor sees only the lower face, the ceiling
// only the upper one. One patch a face, and 4 × 4 a face (twins paired by centroid).
TEST(RaycastRows, TwoSidedPlateShowsBothFrontsAndLeaksNothing) {
    std::vector<NamedPolygon> polys = test::inward_box(1, 1, 1);
    polys.push_back(test::square_z("plate_up", 0.5, true, 0.5, Vec3(0.25, 0.25, 0)));
    polys.push_back(test::square_z("plate_down", 0.5, false, 0.5, Vec3(0.25, 0.25, 0)));
    for (const double edge : {1.0, 0.125}) {
        const Scene scene = test::make_scene(polys, edge * (1 + 1e-9));
        RaycastRowProvider provider(scene, options(4096));
        const CsrMatrix F = compute_all_rows(provider);
        for (std::uint32_t i = 0; i < scene.size(); ++i) EXPECT_NEAR(F.row(i).sum(), 1.0, 1e-4) << "row " << i;
        const auto G = object_form_factors(F, scene);
        const std::size_t up = object_index(scene, "plate_up"), down = object_index(scene, "plate_down"),
                          floor = object_index(scene, "z0"), ceiling = object_index(scene, "z1");
        EXPECT_GT(G[floor][down], 0.1) << "edge " << edge;
        EXPECT_EQ(G[floor][up], 0.0) << "edge " << edge;
        EXPECT_GT(G[ceiling][up], 0.1) << "edge " << edge;
        EXPECT_EQ(G[ceiling][down], 0.0) << "edge " << edge;
    }
}

// The same with a plate of 72 × 72 patches a side (more than the 4,096 cells the first pairing,
// a scan of cells², left unpaired): rows of the ceiling patches above the plate and the floor
// patches below it, which see it most, sum to 1 within the bound above. Unpaired, about half of
// their plate hits land on a back face and are absorbed: the ceiling sees the plate at about
// 0.2, so their rows would sum to about 0.9.
TEST(RaycastRows, LargeTwoSidedPlatePairsEveryPatch) {
    std::vector<NamedPolygon> polys = test::inward_box(1, 1, 1);
    polys.push_back(test::square_z("plate_up", 0.5, true, 0.5, Vec3(0.25, 0.25, 0)));
    polys.push_back(test::square_z("plate_down", 0.5, false, 0.5, Vec3(0.25, 0.25, 0)));
    const Scene scene = test::make_scene(polys, (0.5 / 72) * (1 + 1e-9));
    const std::size_t up = object_index(scene, "plate_up"), down = object_index(scene, "plate_down");
    std::size_t plate = 0;
    for (const Patch& p : scene.patches) plate += p.object == up;
    ASSERT_EQ(plate, 72u * 72u);
    RaycastRowProvider provider(scene, options(4096));
    RaycastRowProvider::RowScratch scratch;
    scratch.acc.assign(scene.size(), 0.0);
    const std::size_t floor = object_index(scene, "z0"), ceiling = object_index(scene, "z1");
    int rows = 0;
    for (std::uint32_t i = 0; i < scene.size(); i += 97) {
        const Patch& p = scene.patches[i];
        if ((p.object != floor && p.object != ceiling) || std::abs(p.centroid.x - 0.5) > 0.2 ||
            std::abs(p.centroid.y - 0.5) > 0.2)
            continue;
        SparseRow row;
        provider.cast_row(i, row, scratch);
        double on_plate = 0;
        for (std::size_t k = 0; k < row.col.size(); ++k) {
            const std::size_t o = scene.patches[row.col[k]].object;
            on_plate += row.val[k] * (o == up || o == down);
            EXPECT_NE(o, p.object == floor ? up : down) << "row " << i << " sees the plate's far side";
        }
        EXPECT_NEAR(row.sum(), 1.0, 1e-4) << "row " << i;
        EXPECT_GT(on_plate, 0.1) << "row " << i;
        ++rows;
    }
    EXPECT_GT(rows, 20);
}

TEST(RaycastRows, ZeroRaysIsAnInputError) {
    const Scene scene = test::make_scene({test::square_z("a", 0.0, true)}, 1.0);
    EXPECT_THROW(RaycastRowProvider(scene, options(0)), InputError);
}

}  // namespace
}  // namespace ffcube
