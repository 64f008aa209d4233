// Row blocks of about equal estimated cost (pipeline/row_partition.hpp), how MPI ranks share rows.
#include <gtest/gtest.h>

#include <algorithm>
#include <numeric>

#include "ffcube/pipeline/row_partition.hpp"
#include "ffcube/scene/builtin.hpp"
#include "ffcube/scene/mesher.hpp"

namespace ffcube {
namespace {

double block_sum(std::span<const double> cost, std::uint32_t a, std::uint32_t b) {
    return std::accumulate(cost.begin() + a, cost.begin() + b, 0.0);
}

TEST(RowPartition, EqualCostsGiveEqualBlocks) {
    const std::vector<double> cost(100, 1.0);
    EXPECT_EQ(balanced_row_blocks(cost, 1), (std::vector<std::uint32_t>{0, 100}));
    EXPECT_EQ(balanced_row_blocks(cost, 4), (std::vector<std::uint32_t>{0, 25, 50, 75, 100}));
    // 100 rows in 3: targets 33.3 and 66.7; a row goes to the block that holds most of it.
    EXPECT_EQ(balanced_row_blocks(cost, 3), (std::vector<std::uint32_t>{0, 33, 67, 100}));
    // More parts than rows: empty blocks, every row still owned once.
    const std::vector<std::uint32_t> b = balanced_row_blocks(std::vector<double>(3, 1.0), 5);
    EXPECT_EQ(b.front(), 0u);
    EXPECT_EQ(b.back(), 3u);
    EXPECT_TRUE(std::is_sorted(b.begin(), b.end()));
}

TEST(RowPartition, BlocksAreWithinHalfARowOfTheirShare) {
    // Costs 1..200: a block boundary sits where the running sum crosses r/K of the total, give or
    // take half of the row at the boundary, so each block's sum is its share ± one row's cost.
    std::vector<double> cost(200);
    for (std::size_t i = 0; i < cost.size(); ++i) cost[i] = double(i + 1);
    const double total = block_sum(cost, 0, 200);
    for (unsigned k : {2u, 3u, 7u}) {
        const std::vector<std::uint32_t> b = balanced_row_blocks(cost, k);
        ASSERT_EQ(b.size(), k + 1);
        for (unsigned r = 0; r < k; ++r)
            EXPECT_NEAR(block_sum(cost, b[r], b[r + 1]), total / k, 200.0) << "k " << k << " block " << r;
        // The expensive rows are at the end: the last block has fewer rows than the first.
        EXPECT_LT(b[k] - b[k - 1], b[1] - b[0]);
    }
}

TEST(RowPartition, CostFollowsThePiecesInFront) {
    // Two unit squares facing each other (one piece each) and a third behind the first, facing
    // away from both: rows of the outward square see no piece in front of their plane.
    ObjModel m;
    m.source = "three squares";
    m.positions = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0},   // z = 0, normal +z
                   {0, 0, 1}, {0, 1, 1}, {1, 1, 1}, {1, 0, 1},   // z = 1, normal −z
                   {0, 0, -1}, {0, 1, -1}, {1, 1, -1}, {1, 0, -1}};  // z = −1, normal −z
    m.objects = {"all"};
    m.materials = {Material{}};
    for (std::uint32_t f = 0; f < 3; ++f) m.faces.push_back(ObjFace{{4 * f, 4 * f + 1, 4 * f + 2, 4 * f + 3}, 0, 0, f + 1});
    MeshOptions mo;
    mo.subdivide = false;
    const Scene s = build_scene(m, mo);
    ASSERT_EQ(s.size(), 3u);
    RowOptions o;
    o.resolution = 64;
    const std::vector<double> cost = estimate_row_costs(s, o);
    const double pixels = 3.0 * 64 * 64 * 5;  // the model's constants (row_partition.cpp)
    // Square 0 (z = 0, +z) has the square at z = 1 in front; square 1 (z = 1, −z) has squares 0 and 2;
    // square 2 (z = −1, −z) none. Each piece in front 200 ns, each behind 10 ns.
    EXPECT_DOUBLE_EQ(cost[0], pixels + 200 * 1 + 10 * 2);
    EXPECT_DOUBLE_EQ(cost[1], pixels + 200 * 2 + 10 * 1);
    EXPECT_DOUBLE_EQ(cost[2], pixels + 10 * 3);
    o.method = RowMethod::Raycast;
    const std::vector<double> rays = estimate_row_costs(s, o);
    EXPECT_EQ(rays[0], rays[2]);
}

TEST(RowPartition, CornellBoxSplitsEveryRowOnce) {
    MeshOptions mo;
    mo.target_patches = 500;
    const Scene s = build_scene(load_cornell_box(), mo);
    const std::vector<double> cost = estimate_row_costs(s, RowOptions{});
    ASSERT_EQ(cost.size(), s.size());
    const std::vector<std::uint32_t> b = balanced_row_blocks(cost, 4);
    EXPECT_EQ(b.front(), 0u);
    EXPECT_EQ(b.back(), s.size());
    EXPECT_TRUE(std::is_sorted(b.begin(), b.end()));
    const double total = block_sum(cost, 0, static_cast<std::uint32_t>(s.size()));
    const double most = *std::max_element(cost.begin(), cost.end());
    for (unsigned r = 0; r < 4; ++r) EXPECT_NEAR(block_sum(cost, b[r], b[r + 1]), total / 4, most);
}

}  // namespace
}  // namespace ffcube
