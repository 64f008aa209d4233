// Occlusion culling (gl/hemicube_worker.cpp, Worker::occlude): in a hemicube of many pieces, the
// pieces wholly behind the occluders drawn first are left out. It must never change a pixel: the
// rows with it are compared bit for bit with the rows drawing every piece, on a small city of
// boxes where most of the blocks hide others, for centre hemicubes and for sub-hemicubes.
#include <gtest/gtest.h>

#include <algorithm>
#include <numeric>

#include "ffcube/gl/hemicube_provider.hpp"
#include "support/planned_rows.hpp"
#include "support/scenes.hpp"

namespace ffcube {
namespace {

// A grid of g × g blocks (1 × 1 footprint, heights 1–4 in a fixed pattern) two units apart, with
// outward walls and roofs, on a ground of unit tiles filling the streets between them: every
// face one patch (max_patch_edge 2), 5 pieces a block plus the tiles.
Scene block_city(int g) {
    std::vector<NamedPolygon> polys;
    for (int bx = 0; bx < g; ++bx)
        for (int by = 0; by < g; ++by) {
            const double x0 = 2.0 * bx, y0 = 2.0 * by, x1 = x0 + 1, y1 = y0 + 1;
            const double h = 1 + (bx * 7 + by * 3) % 4;
            const Vec3 a(x0, y0, 0), b(x1, y0, 0), c(x1, y1, 0), d(x0, y1, 0);
            const Vec3 A(x0, y0, h), B(x1, y0, h), C(x1, y1, h), D(x0, y1, h);
            polys.push_back({"roofs", {A, B, C, D}});   // +z
            polys.push_back({"walls", {a, b, B, A}});   // -y
            polys.push_back({"walls", {b, c, C, B}});   // +x
            polys.push_back({"walls", {c, d, D, C}});   // +y
            polys.push_back({"walls", {d, a, A, D}});   // -x
            // The street tiles east, north and north-east of the block.
            for (const auto& [ox, oy] : {std::pair{1.0, 0.0}, std::pair{0.0, 1.0}, std::pair{1.0, 1.0}})
                polys.push_back(test::square_z("ground", 0, true, 1.0, Vec3(x0 + ox, y0 + oy, 0)));
        }
    return test::make_scene(polys, 2.0);
}

struct Rows {
    std::vector<std::vector<std::uint32_t>> col;
    std::vector<std::vector<double>> val;
    HemicubeStats stats;
};

Rows compute(const Scene& s, bool occlusion, RowProvider::RowPlan plan, unsigned threads, bool nodes = true) {
    HemicubeOptions o;
    o.resolution = 64;
    o.threads = threads;
    o.occlusion_culling = occlusion;
    o.occlusion_nodes = nodes;
    test::AllRows all = test::all_rows(s, o, plan);
    Rows r;
    for (SparseRow& row : all.rows) {
        r.col.push_back(std::move(row.col));
        r.val.push_back(std::move(row.val));
    }
    r.stats = all.stats;
    return r;
}

std::uint64_t occluded(const HemicubeStats& st) {
    return std::accumulate(st.pieces_occluded.begin(), st.pieces_occluded.end(), std::uint64_t{0});
}

TEST(OcclusionCulling, RowsAreBitwiseTheSameAsDrawingEveryPiece) {
    const Scene s = block_city(8);  // 64 blocks: 512 pieces
    ASSERT_EQ(s.grids.size(), 512u);
    for (const auto plan : {RowProvider::RowPlan::centre, RowProvider::RowPlan::sampled}) {
        const Rows all = compute(s, false, plan, 2);
        const Rows culled = compute(s, true, plan, 2);
        std::size_t nonzero = 0;
        for (std::uint32_t i = 0; i < s.size(); ++i) {
            ASSERT_EQ(all.col[i], culled.col[i]) << "row " << i;
            ASSERT_EQ(all.val[i], culled.val[i]) << "row " << i;
            nonzero += all.col[i].size();
        }
        EXPECT_GT(nonzero, 10 * s.size());
        // It did leave pieces out (else this compares nothing): the blocks hide most of the
        // city from the street tiles and the lower walls.
        EXPECT_EQ(all.stats.occlusion_hemicubes, 0u);
        EXPECT_EQ(occluded(all.stats), 0u);
        EXPECT_GT(culled.stats.occlusion_hemicubes, all.stats.hemicubes / 2);
        const auto drawn = std::accumulate(all.stats.pieces_drawn.begin(), all.stats.pieces_drawn.end(), std::uint64_t{0});
        EXPECT_GT(occluded(culled.stats), drawn / 5) << "of " << drawn << " pieces × faces drawn without culling";
        // Every piece drawn or left out, face by face, as without it.
        for (std::size_t f = 0; f < 5; ++f)
            EXPECT_EQ(culled.stats.pieces_drawn[f] + culled.stats.pieces_occluded[f], all.stats.pieces_drawn[f]);
    }
}

// Which pieces are left out depends on what the worker drew before (its last hemicube's pieces
// are the next one's occluders), so on the scheduling; the rows must not.
TEST(OcclusionCulling, RowsDoNotDependOnTheWorkerCount) {
    const Scene s = block_city(7);
    const Rows one = compute(s, true, RowProvider::RowPlan::centre, 1);
    const Rows two = compute(s, true, RowProvider::RowPlan::centre, 2);
    EXPECT_EQ(one.col, two.col);
    EXPECT_EQ(one.val, two.val);
}

// Whole hierarchy nodes left out (hemicube/occlusion.hpp, hide_hidden_nodes) only spare the piece
// tests: on one worker (the same occluders hemicube after hemicube) every face of every piece is
// left out or drawn exactly as when each piece is tested, and the rows are the same bits.
TEST(OcclusionCulling, HiddenNodesLeaveOutExactlyThePiecesTheTestsWould) {
    const Scene s = block_city(8);
    for (const auto plan : {RowProvider::RowPlan::centre, RowProvider::RowPlan::sampled}) {
        const Rows each = compute(s, true, plan, 1, false);
        const Rows nodes = compute(s, true, plan, 1, true);
        EXPECT_EQ(each.col, nodes.col);
        EXPECT_EQ(each.val, nodes.val);
        EXPECT_EQ(each.stats.pieces_occluded, nodes.stats.pieces_occluded);
        EXPECT_EQ(each.stats.pieces_drawn, nodes.stats.pieces_drawn);
        EXPECT_EQ(each.stats.nodes_occluded, 0u);
        // The nodes did the work (else this compares nothing): most of what is left out.
        EXPECT_GT(nodes.stats.nodes_occluded, 0u);
        EXPECT_GT(nodes.stats.pieces_occluded_by_node, occluded(nodes.stats) / 4)
            << nodes.stats.pieces_occluded_by_node << " of " << occluded(nodes.stats);
    }
}

}  // namespace
}  // namespace ffcube
