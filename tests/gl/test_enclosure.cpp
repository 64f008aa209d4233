// The enclosure drawn without the depth test (hemicube/pieces.hpp, Enclosure;
// HemicubeOptions::enclosure_without_depth): from an eye inside a convex room or above a flat
// ground, the room's walls or the ground never overlap on the screen and everything else lies in
// front of them, so drawing them first without the depth test gives the picture of depth-testing
// every piece. Where nothing touches the enclosure the rows are the same bits (a closed box with a
// two-sided plate and a floating block, centre hemicubes and sub-hemicubes). Where a piece stands
// on it (a block on the floor, walls on a city's ground), the only pixels that may change lie on
// the contact line: there the depth test decided a tie by rounding (the block's lowest fragments
// against the floor at the same depth), and now the standing piece, which is in front, wins.
#include <gtest/gtest.h>

#include <algorithm>
#include <numeric>
#include <cmath>
#include <cstdio>

#include "ffcube/gl/hemicube_provider.hpp"
#include "ffcube/hemicube/pieces.hpp"
#include "support/planned_rows.hpp"
#include "support/scenes.hpp"

namespace ffcube {
namespace {

// The closed unit box (inward walls), a two-sided plate floating in it, and (block) a closed
// block (outward faces, no bottom) standing on the floor, or floating `lift` above it.
Scene box_plate_block(double lift, bool block = true) {
    std::vector<NamedPolygon> polys = test::inward_box(1, 1, 1);
    polys.push_back(test::square_z("plate", 0.6, true, 0.4, Vec3(0.3, 0.3, 0)));
    polys.push_back(test::square_z("plate", 0.6, false, 0.4, Vec3(0.3, 0.3, 0)));
    if (!block) return test::make_scene(polys, 0.125);
    const Vec3 z(0, 0, lift), a = Vec3(.1, .1, 0) + z, b = Vec3(.3, .1, 0) + z, c = Vec3(.3, .3, 0) + z,
               d = Vec3(.1, .3, 0) + z, h(0, 0, .25);
    polys.push_back({"block", {a + h, b + h, c + h, d + h}});
    polys.push_back({"block", {a, b, b + h, a + h}});
    polys.push_back({"block", {b, c, c + h, b + h}});
    polys.push_back({"block", {c, d, d + h, c + h}});
    polys.push_back({"block", {d, a, a + h, d + h}});
    return test::make_scene(polys, 0.125);
}

// The closed unit box with every wall cut into 2 × k² triangles, each one patch (as an STL export
// writes it: 12k² pieces, enough for occlusion culling), and a two-sided plate of two triangles a
// side: the walls are a closed enclosure, the plate one plane of twins.
Scene triangulated_box_plate(int k) {
    std::vector<NamedPolygon> polys;
    const auto wall = [&](Vec3 o, Vec3 u, Vec3 v, int n, const std::string& name) {
        const auto p = [&](int i, int j) { return o + u * (static_cast<double>(i) / n) + v * (static_cast<double>(j) / n); };
        for (int i = 0; i < n; ++i)
            for (int j = 0; j < n; ++j) {
                polys.push_back({name, {p(i, j), p(i + 1, j), p(i + 1, j + 1)}});
                polys.push_back({name, {p(i, j), p(i + 1, j + 1), p(i, j + 1)}});
            }
    };
    wall(Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0, 1, 0), k, "floor");
    wall(Vec3(0, 0, 1), Vec3(0, 1, 0), Vec3(1, 0, 0), k, "ceiling");
    wall(Vec3(0, 0, 0), Vec3(0, 1, 0), Vec3(0, 0, 1), k, "x0");
    wall(Vec3(1, 0, 0), Vec3(0, 0, 1), Vec3(0, 1, 0), k, "x1");
    wall(Vec3(0, 0, 0), Vec3(0, 0, 1), Vec3(1, 0, 0), k, "y0");
    wall(Vec3(0, 1, 0), Vec3(1, 0, 0), Vec3(0, 0, 1), k, "y1");
    wall(Vec3(.3, .3, .55), Vec3(.4, 0, 0), Vec3(0, .4, 0), 1, "plate");
    wall(Vec3(.3, .3, .55), Vec3(0, .4, 0), Vec3(.4, 0, 0), 1, "plate");
    return test::make_scene(polys, 10.0);
}

// Blocks of heights 1–3 two units apart on street tiles (as test_occlusion's city).
Scene block_city(int g) {
    std::vector<NamedPolygon> polys;
    for (int bx = 0; bx < g; ++bx)
        for (int by = 0; by < g; ++by) {
            const double x0 = 2.0 * bx, y0 = 2.0 * by, x1 = x0 + 1, y1 = y0 + 1;
            const double h = 1 + (bx * 5 + by) % 3;
            const Vec3 a(x0, y0, 0), b(x1, y0, 0), c(x1, y1, 0), d(x0, y1, 0);
            const Vec3 A(x0, y0, h), B(x1, y0, h), C(x1, y1, h), D(x0, y1, h);
            polys.push_back({"roofs", {A, B, C, D}});
            polys.push_back({"walls", {a, b, B, A}});
            polys.push_back({"walls", {b, c, C, B}});
            polys.push_back({"walls", {c, d, D, C}});
            polys.push_back({"walls", {d, a, A, D}});
            for (const auto& [ox, oy] : {std::pair{1.0, 0.0}, std::pair{0.0, 1.0}, std::pair{1.0, 1.0}})
                polys.push_back(test::square_z("ground", 0, true, 1.0, Vec3(x0 + ox, y0 + oy, 0)));
        }
    return test::make_scene(polys, 0.5);
}

HemicubeOptions options(bool enclosure) {
    HemicubeOptions o;
    o.resolution = 64;
    o.threads = 2;
    o.enclosure_without_depth = enclosure;
    return o;
}

// A box with a two-sided plate and a floating block: the walls drawn without the depth test,
// the plate and the block with it; without the block, nothing needs the depth test. The box is
// closed, so its hemicubes are not cleared either.
TEST(Enclosure, ClosedBoxRowsAreBitwiseTheSameAsDepthTestingEverything) {
    for (const bool block : {true, false}) {
        const Scene s = box_plate_block(0.05, block);
        // Closed: no hemicube is cleared, and a pixel left undrawn would show the last one's id.
        ASSERT_TRUE(find_enclosure(s.grids).closed);
        for (const auto plan : {RowProvider::RowPlan::centre, RowProvider::RowPlan::sampled}) {
            const test::AllRows depth = test::all_rows(s, options(false), plan);
            const test::AllRows free = test::all_rows(s, options(true), plan);
            std::size_t nonzero = 0;
            for (std::uint32_t i = 0; i < s.size(); ++i) {
                ASSERT_EQ(depth.rows[i].col, free.rows[i].col) << "row " << i;
                ASSERT_EQ(depth.rows[i].val, free.rows[i].val) << "row " << i;
                nonzero += depth.rows[i].col.size();
            }
            EXPECT_GT(nonzero, 10 * s.size());
            // Every hemicube's eye lay inside (else this compares nothing) and drew the walls so:
            // at least the four beside the wall opposite (the block's own patches see more).
            EXPECT_EQ(depth.stats.enclosure_hemicubes, 0u);
            EXPECT_EQ(free.stats.enclosure_hemicubes, free.stats.hemicubes);
            EXPECT_GE(free.stats.enclosure_pieces_drawn, 4 * free.stats.hemicubes);
            EXPECT_EQ(free.stats.depth_free_hemicubes, block ? 0u : free.stats.hemicubes);
        }
    }
}

// An STL-like closed box of 864 triangles around a two-sided plate: no hemicube needs the depth
// test or a clear, while occlusion culling (128 pieces or more in view) draws its occluders' depth
// first. The same bits as depth-testing everything.
TEST(Enclosure, TriangulatedBoxWithOcclusionCullingIsBitwiseTheSame) {
    const Scene s = triangulated_box_plate(6);
    ASSERT_EQ(s.grids.size(), 6u * 72 + 4);
    const Enclosure en = find_enclosure(s.grids, find_twins(s.grids));
    ASSERT_EQ(en.planes.size(), 6u);
    ASSERT_TRUE(en.closed);
    ASSERT_TRUE(en.inner_flat);
    // One worker: each hemicube's occluders (what the last one showed) are the same either way.
    HemicubeOptions off = options(false), on = options(true);
    off.threads = on.threads = 1;
    const test::AllRows depth = test::all_rows(s, off, RowProvider::RowPlan::centre);
    const test::AllRows free = test::all_rows(s, on, RowProvider::RowPlan::centre);
    for (std::uint32_t i = 0; i < s.size(); ++i) {
        ASSERT_EQ(depth.rows[i].col, free.rows[i].col) << "row " << i;
        ASSERT_EQ(depth.rows[i].val, free.rows[i].val) << "row " << i;
    }
    EXPECT_EQ(free.stats.depth_free_hemicubes, free.stats.hemicubes);
    EXPECT_GT(free.stats.occlusion_hemicubes, 0u);
    // The occluders' pass keeps its depth test: the plate hides exactly the wall triangles it hid
    // with the depth test everywhere (a pass drawn without it would leave no depth: 4 of 729).
    const auto occluded = [](const HemicubeStats& st) {
        return std::accumulate(st.pieces_occluded.begin(), st.pieces_occluded.end(), std::uint64_t{0});
    };
    EXPECT_GT(occluded(depth.stats), 100u);
    EXPECT_EQ(occluded(free.stats), occluded(depth.stats));
}

// Every hemicube's item buffer with and without: a pixel may differ only where the depth test
// showed an enclosure piece and now a piece standing on it shows, on the edge of that piece's
// region in the depth-tested picture (a 4-neighbour shows it there); at most a line of pixels per
// contact edge in view, 3N a line across the whole atlas.
void expect_only_contact_pixels_change(const Scene& s, std::size_t contact_edges) {
    const Enclosure en = find_enclosure(s.grids);
    ASSERT_FALSE(en.piece.empty());
    std::vector<std::uint8_t> on_enclosure(s.size());
    for (std::size_t g = 0; g < s.grids.size(); ++g) {
        const std::size_t end = g + 1 < s.grids.size() ? s.grids[g + 1].first_patch : s.size();
        for (std::size_t p = s.grids[g].first_patch; p < end; ++p) on_enclosure[p] = en.piece[g];
    }
    HemicubeOptions o = options(false);
    o.threads = 1;
    HemicubeRowProvider depth_provider(s, o);
    o.enclosure_without_depth = true;
    HemicubeRowProvider free_provider(s, o);
    const int w = 3 * 64, h = 64;
    std::size_t changed = 0, worst = 0;
    for (std::uint32_t i = 0; i < s.size(); ++i) {
        const std::vector<std::uint32_t> a = depth_provider.item_buffer(i), b = free_provider.item_buffer(i);
        ASSERT_EQ(a.size(), static_cast<std::size_t>(w * h));
        std::size_t here = 0;
        for (int y = 0; y < h; ++y)
            for (int x = 0; x < w; ++x) {
                const std::size_t k = static_cast<std::size_t>(y * w + x);
                if (a[k] == b[k]) continue;
                ++here;
                ASSERT_TRUE(a[k] >= 1 && a[k] - 1 < s.size() && on_enclosure[a[k] - 1]) << "row " << i << " pixel " << x << "," << y;
                ASSERT_TRUE(b[k] >= 1 && b[k] - 1 < s.size() && !on_enclosure[b[k] - 1]) << "row " << i << " pixel " << x << "," << y;
                bool edge = false;
                for (const auto& [dx, dy] : {std::pair{1, 0}, std::pair{-1, 0}, std::pair{0, 1}, std::pair{0, -1}}) {
                    if (x + dx < 0 || x + dx >= w || y + dy < 0 || y + dy >= h) continue;
                    edge = edge || a[static_cast<std::size_t>((y + dy) * w + x + dx)] == b[k];
                }
                EXPECT_TRUE(edge) << "row " << i << " pixel " << x << "," << y << ": not beside the piece's region";
            }
        changed += here;
        worst = std::max(worst, here);
    }
    EXPECT_LE(worst, contact_edges * static_cast<std::size_t>(w));
    std::printf("pixels changed: %zu in %zu hemicubes, at most %zu in one\n", changed, static_cast<std::size_t>(s.size()), worst);
}

TEST(Enclosure, ABlockOnTheFloorChangesOnlyPixelsOnItsContactLine) {
    expect_only_contact_pixels_change(box_plate_block(0.0), 4);
}

TEST(Enclosure, ACityOnItsGroundChangesOnlyPixelsOnTheContactLines) {
    const Scene s = block_city(4);
    expect_only_contact_pixels_change(s, 4 * 16);
    // Its rows (sub-hemicubes too) are sums of such pictures: the same entries, each moved by
    // at most the pixels above.
    for (const auto plan : {RowProvider::RowPlan::centre, RowProvider::RowPlan::sampled}) {
        const test::AllRows depth = test::all_rows(s, options(false), plan);
        const test::AllRows free = test::all_rows(s, options(true), plan);
        EXPECT_EQ(free.stats.enclosure_hemicubes, free.stats.hemicubes);
        double diff = 0;
        for (std::uint32_t i = 0; i < s.size(); ++i) {
            ASSERT_EQ(depth.rows[i].col.size(), free.rows[i].col.size());
            for (std::size_t k = 0; k < depth.rows[i].val.size(); ++k) diff = std::max(diff, std::abs(depth.rows[i].val[k] - free.rows[i].val[k]));
        }
        // ΔF of one pixel at N = 64 is at most (2/64)² / π (the top face's centre), and a row's
        // entry changes by whole pixels: a bound of 64 pixels an entry.
        EXPECT_LE(diff, 64 * (2.0 / 64) * (2.0 / 64) / 3.141592653589793);
    }
}

}  // namespace
}  // namespace ffcube
