// --method auto by measured costs (issue 40 part 4; pipeline/row_engine.hpp, row costs): the cost
// of a row by each engine as the formula says, the engine of a 4 × 4 row and the whole scene's
// method on either side of the crossover (where the two costs are equal, computed here from the
// formula by hand), and the built-in model keeping the piece-count rule.
#include <gtest/gtest.h>

#include <cmath>
#include <string>
#include <vector>

#include "ffcube/formfactor/row_provider.hpp"
#include "ffcube/pipeline/options.hpp"
#include "ffcube/pipeline/row_engine.hpp"
#include "support/scenes.hpp"

namespace ffcube {
namespace {

using Plan = RowProvider::RowPlan;
using Engine = RowProvider::RowEngine;

CostModel model(double pixel_ns, double piece_ns, double ray_ns) {
    CostModel m;
    m.pixel_ns = pixel_ns;
    m.piece_ns = piece_ns;
    m.ray_ns = ray_ns;
    m.source = "costs.json";  // a file's model: the costs decide
    return m;
}

// Separate unit tiles, one piece each; `edge` 2: one patch a tile, 0.4: 9 patches a tile.
Scene tiles(std::size_t n, double edge) {
    std::vector<test::NamedPolygon> polys;
    for (std::size_t k = 0; k < n; ++k) {
        const double x = static_cast<double>(k % 40) * 1.5, y = static_cast<double>(k / 40) * 1.5;
        polys.push_back({"t" + std::to_string(k), {{x, y, 0}, {x + 1, y, 0}, {x + 1, y + 1, 0}, {x, y + 1, 0}}});
    }
    return test::make_scene(polys, edge * (1 + 1e-9));
}

// The formula, by hand: a hemicube row draws 1, 4 or 16 hemicubes of 3N² pixels and every piece;
// a ray-cast row its rays; rows refined to E cast the budget 2^⌈log2(64/E)⌉.
TEST(MethodCosts, RowCostsAreTheFormula) {
    const CostModel m = model(2.0, 300.0, 50.0);
    // N = 64, 1,000 pieces: 3 × 4,096 × 2 + 1,000 × 300 = 324,576 ns a hemicube.
    EXPECT_DOUBLE_EQ(hemicube_row_ns(m, Plan::centre, 64, 1000), 324576.0);
    EXPECT_DOUBLE_EQ(hemicube_row_ns(m, Plan::sampled, 64, 1000), 4 * 324576.0);
    EXPECT_DOUBLE_EQ(hemicube_row_ns(m, Plan::sampled_fine, 64, 1000), 16 * 324576.0);
    EXPECT_DOUBLE_EQ(hemicube_row_ns(m, Plan::skip, 64, 1000), 0.0);
    EXPECT_DOUBLE_EQ(ray_row_ns(m, 32768), 32768 * 50.0);
    EXPECT_EQ(expected_row_rays(1e-3, 999), 65536u);   // 64/E = 64,000 → 2^16
    EXPECT_EQ(expected_row_rays(1e-4, 999), 1048576u); // 640,000 → 2^20
    EXPECT_EQ(expected_row_rays(0.0, 999), 999u);      // no tolerance: the fixed count
}

// A 4 × 4 row goes to the rays exactly where its rays cost less than its 16 hemicubes: ray_ns at
// the crossover is 16 (3N² pixel_ns + P piece_ns) / R; 1% either side flips the choice. Other
// plans stay drawn; obstruction-only surfaces and --fine-rows hemicubes keep the hemicubes.
TEST(MethodCosts, FineRowsFollowTheCrossover) {
    SceneFacts f;
    f.resolution = 64;
    f.pieces = 50;  // below every threshold of the piece-count rule: the costs alone decide
    f.patches = 50;
    const std::uint64_t rays = 8192;  // default_fine_row_rays(64) = max(2,048, min(8,192, 32,768))
    ASSERT_EQ(default_fine_row_rays(64), rays);
    const double pixel_ns = 1.0, piece_ns = 100.0;
    const double crossover = 16 * (3.0 * 64 * 64 * pixel_ns + 50 * piece_ns) / static_cast<double>(rays);
    f.costs = model(pixel_ns, piece_ns, 0.99 * crossover);
    EXPECT_EQ(engine_for_row(FineRows::automatic, 0, f, Plan::sampled_fine).engine, Engine::rays);
    EXPECT_EQ(engine_for_row(FineRows::automatic, 0, f, Plan::sampled_fine).rays, rays);
    for (const Plan p : {Plan::centre, Plan::sampled, Plan::skip})
        EXPECT_EQ(engine_for_row(FineRows::automatic, 0, f, p).engine, Engine::provider);
    EXPECT_EQ(engine_for_row(FineRows::hemicubes, 0, f, Plan::sampled_fine).engine, Engine::provider);
    // --fine-row-rays doubles the rays: the crossover moves to half the ray cost.
    EXPECT_EQ(engine_for_row(FineRows::automatic, 2 * rays, f, Plan::sampled_fine).engine, Engine::provider);
    f.costs = model(pixel_ns, piece_ns, 1.01 * crossover);
    EXPECT_EQ(engine_for_row(FineRows::automatic, 0, f, Plan::sampled_fine).engine, Engine::provider);
    EXPECT_EQ(engine_for_row(FineRows::rays, 0, f, Plan::sampled_fine).engine, Engine::rays);
    f.costs = model(pixel_ns, piece_ns, 0.5 * crossover);
    f.obstructions = true;
    EXPECT_EQ(engine_for_row(FineRows::automatic, 0, f, Plan::sampled_fine).engine, Engine::provider);
    // The built-in model keeps the piece-count rule: 50 pieces are too few for rays there,
    // whatever its costs would say.
    f.obstructions = false;
    f.costs = CostModel{};
    EXPECT_EQ(engine_for_row(FineRows::automatic, 0, f, Plan::sampled_fine).engine, Engine::provider);
}

// The whole scene: rays where a ray-cast row (at the tolerance's budget) costs less than the mesh's
// typical hemicube row, 16 hemicubes on a mesh of one patch a piece, 1 on a subdivided one.
TEST(MethodCosts, MethodAutoFollowsTheSceneCrossover) {
    RowOptions o;
    set_row_method("auto", o);
    o.resolution = 64;
    o.tolerance = 1e-3;  // rays at the budget: 65,536
    const double pixel_ns = 1.0, piece_ns = 100.0;
    const double rays = 65536;
    struct Case {
        Scene scene;
        double hemicubes;
    };
    const Scene city = tiles(120, 2.0);       // 120 pieces, one patch each: costed at 16 hemicubes
    const Scene subdivided = tiles(20, 0.4);  // 20 pieces of 9 patches: costed at 1
    ASSERT_EQ(city.grids.size(), 120u);
    ASSERT_EQ(subdivided.grids.size(), 20u);
    ASSERT_EQ(subdivided.patches.size(), 180u);
    for (const auto& [scene, hemicubes] : {std::pair<const Scene&, double>{city, 16.0}, {subdivided, 1.0}}) {
        const double pieces = static_cast<double>(scene.grids.size());
        const double crossover = hemicubes * (3.0 * 64 * 64 * pixel_ns + pieces * piece_ns) / rays;
        o.cost_model = model(pixel_ns, piece_ns, 0.99 * crossover);
        RowOptions r = resolve_row_method(o, scene);
        EXPECT_EQ(r.method, RowMethod::Raycast) << pieces;
        EXPECT_EQ(r.method_costs.hemicubes, static_cast<unsigned>(hemicubes));
        EXPECT_DOUBLE_EQ(r.method_costs.rays_ns, rays * 0.99 * crossover);
        EXPECT_EQ(r.method_choice.rfind("auto by costs.json: a row of ", 0), 0u) << r.method_choice;
        o.cost_model = model(pixel_ns, piece_ns, 1.01 * crossover);
        r = resolve_row_method(o, scene);
        EXPECT_EQ(r.method, RowMethod::Hemicube) << pieces;
        // Without a tolerance the fixed count (the fine-row default at N = 64, 8,192) is costed:
        // 8 × fewer rays than the budget, so rays again.
        RowOptions fixed = o;
        fixed.tolerance = 0;
        EXPECT_EQ(resolve_row_method(fixed, scene).method, RowMethod::Raycast) << pieces;
        EXPECT_EQ(resolve_row_method(fixed, scene).rays, 8192u);
    }
    // A GPU-like model (0.01 ns a pixel, 10 ns a piece, 60 ns a ray): hemicubes on the city, 16 ×
    // (123 + 1,200) ns against 3.9 ms of rays; a slow pixel (1,000 ns): rays on the subdivided
    // scene, 12.3 ms a hemicube against 3.9 ms.
    o.cost_model = model(0.01, 10, 60);
    EXPECT_EQ(resolve_row_method(o, city).method, RowMethod::Hemicube);
    o.cost_model = model(1000, 500, 60);
    EXPECT_EQ(resolve_row_method(o, subdivided).method, RowMethod::Raycast);
    // Never with --fine-rows hemicubes.
    o.fine_rows = FineRows::hemicubes;
    EXPECT_EQ(resolve_row_method(o, subdivided).method, RowMethod::Hemicube);
}

}  // namespace
}  // namespace ffcube
