// Rows planned at 4 × 4 sub-hemicubes ray-cast instead (the driver's engine_for_row,
// pipeline/row_engine.hpp; --fine-rows; docs/accuracy.md, "Rows an occluder touches, by rays"):
// such a row is the ray caster's row, the same bits, on either kind of worker; other rows are the
// hemicube's, untouched; the automatic choice follows the scene's pieces and keeps hemicubes
// where obstruction-only surfaces are; and through the correction the rows are as close to an
// independent reference as sub-hemicubes.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <string>
#include <utility>
#include <vector>

#include "ffcube/accuracy/near_field.hpp"
#include "ffcube/core/error.hpp"
#include "ffcube/formfactor/checks.hpp"
#include "ffcube/gl/hemicube_provider.hpp"
#include "ffcube/pipeline/row_engine.hpp"
#include "ffcube/raycast/raycast_provider.hpp"
#include "ffcube/scene/mesher.hpp"
#include "ffcube/scene/polygons.hpp"
#include "support/scenes.hpp"

namespace ffcube {
namespace {

using Plan = RowProvider::RowPlan;

Scene make(const std::vector<NamedPolygon>& polys, double edge) {
    MeshOptions mo;
    mo.max_patch_edge = edge;
    return build_scene(model_from_polygons(polys, "<fine rows test>"), mo);
}

// A floor and a wall along one of its edges, 4 × 4 patches each (two pieces).
Scene corner() {
    return make({{"floor", {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}}},
                 {"wall", {{0, 0, 0}, {0, 0, 1}, {1, 0, 1}, {1, 0, 0}}}},
                0.25);
}

// The rows under these plans, as the correction's plan stage hands them to the provider (here
// without sender points: the hemicube's own quadrature points).
std::vector<SparseRow> planned_rows(RowProvider& p, const std::vector<std::uint32_t>& rows, const std::vector<Plan>& plans) {
    std::vector<SparseRow> out;
    RowProvider::RowStages stages;
    stages.plan = [&](std::size_t k, std::uint32_t, RowProvider::RowRequest& r) { r.plan = plans[k]; };
    p.compute_rows_staged(rows, stages, [&](std::uint32_t, const SparseRow& r) { out.push_back(r); });
    return out;
}

// A fine row is exactly the ray caster's row (its rays and seed); a centre row is exactly the
// hemicube's; with workers on threads (a GL context each, in this process) and forked worker
// processes (rows pipelined: the ray-cast row is cast while the child draws the row before) alike.
TEST(FineRowsByRays, AFineRowIsTheRayCastersRowAndOtherRowsTheHemicubes) {
    const Scene s = corner();
    const std::vector<std::uint32_t> rows = {3, 20, 5, 3};
    const std::vector<Plan> plans = {Plan::sampled_fine, Plan::centre, Plan::sampled, Plan::sampled_fine};
    RaycastOptions ro;
    ro.rays = 1000;
    ro.threads = 1;
    ro.seed = 77;
    RaycastRowProvider caster(s, ro);
    SparseRow cast;
    caster.compute_row(3, cast);
    ASSERT_GT(cast.nnz(), 0u);
    for (const auto& [threads, processes] : {std::pair{1u, false}, std::pair{2u, false}, std::pair{2u, true}}) {
        HemicubeOptions o;
        o.resolution = 64;
        o.threads = threads;
        o.worker_processes = processes;
        o.seed = 77;
        HemicubeRowProvider drawn(s, o);
        RowDriver drawn_driver(s, drawn, FineRows::hemicubes, 0, o.seed);
        const std::vector<SparseRow> ref = planned_rows(drawn_driver, rows, plans);
        HemicubeRowProvider hybrid_hemicube(s, o);
        RowDriver hybrid(s, hybrid_hemicube, FineRows::rays, 1000, o.seed);
        if (!processes) {
            EXPECT_EQ(hybrid_hemicube.workers(), "threads");
        }
        EXPECT_TRUE(hybrid.fine_rows_by_rays());
        EXPECT_EQ(hybrid.fine_row_rays(), 1000u);
        EXPECT_EQ(hybrid.cast_fine_row_rays(), 1000u);
        EXPECT_EQ(drawn_driver.cast_fine_row_rays(), 0u);
        const std::vector<SparseRow> got = planned_rows(hybrid, rows, plans);
        ASSERT_EQ(got.size(), rows.size());
        for (const std::size_t k : {0u, 3u}) {
            EXPECT_EQ(got[k].col, cast.col) << threads << " thread(s), row " << k;
            EXPECT_EQ(got[k].val, cast.val) << threads << " thread(s), row " << k;
        }
        for (const std::size_t k : {1u, 2u}) {
            EXPECT_EQ(got[k].col, ref[k].col) << threads << " thread(s), row " << k;
            EXPECT_EQ(got[k].val, ref[k].val) << threads << " thread(s), row " << k;
        }
        const HemicubeStats st = hybrid_hemicube.stats();
        EXPECT_EQ(st.fine_rows_cast, 2u);
        EXPECT_EQ(st.hemicubes, drawn.stats().hemicubes - 2 * 16);  // the two rows' 16 sub-hemicubes each
    }
}

// automatic: rays where rays_preferred (kFineRowsByRaysMinPieces pieces or more, or
// kRaysMinMeshPieces of one patch each), hemicubes below; never where the scene has
// obstruction-only surfaces (the ray caster credits either side of those), where an explicit
// `rays` is refused. Only rows planned at 4 × 4 go to the rays. The default ray count follows the
// resolution. engine_for_row is pure: the scene's facts alone decide, as here by hand.
TEST(FineRowsByRays, AutomaticFollowsThePiecesAndKeepsHemicubesWithObstructions) {
    using Engine = RowProvider::RowEngine;
    const auto engine = [](FineRows f, const SceneFacts& facts, Plan plan = Plan::sampled_fine) {
        return engine_for_row(f, 0, facts, plan).engine;
    };
    SceneFacts facts;
    facts.resolution = 64;
    facts.pieces = kRaysMinMeshPieces - 1;
    facts.patches = facts.pieces;
    EXPECT_EQ(engine(FineRows::automatic, facts), Engine::provider);
    facts.pieces = kRaysMinMeshPieces;  // one patch a piece
    facts.patches = facts.pieces;
    EXPECT_EQ(engine(FineRows::automatic, facts), Engine::rays);
    facts.patches = kRaysMaxPatchesPerPiece * facts.pieces + 1;  // more than 4 patches a piece
    EXPECT_EQ(engine(FineRows::automatic, facts), Engine::provider);
    facts.pieces = kFineRowsByRaysMinPieces;
    facts.patches = 100 * facts.pieces;
    EXPECT_EQ(engine(FineRows::automatic, facts), Engine::rays);
    for (const Plan p : {Plan::centre, Plan::sampled, Plan::skip})
        EXPECT_EQ(engine(FineRows::automatic, facts, p), Engine::provider);
    EXPECT_EQ(engine(FineRows::hemicubes, facts), Engine::provider);
    EXPECT_EQ(engine_for_row(FineRows::automatic, 0, facts, Plan::sampled_fine).rays, 8192u);  // max(N²/2, min(2 N², 32,768)), N = 64
    EXPECT_EQ(engine_for_row(FineRows::automatic, 500, facts, Plan::sampled_fine).rays, 500u);
    EXPECT_EQ(default_fine_row_rays(256), 32768u);
    EXPECT_EQ(default_fine_row_rays(512), 131072u);
    facts.obstructions = true;
    EXPECT_EQ(engine(FineRows::automatic, facts), Engine::provider);
    EXPECT_THROW(engine(FineRows::rays, facts), InputError);

    // The same through the driver, from a scene: separate unit tiles on the ground, one piece each.
    const auto tiles = [](std::size_t n) {
        std::vector<NamedPolygon> polys;
        for (std::size_t k = 0; k < n; ++k) {
            const double x = static_cast<double>(k % 40) * 1.5, y = static_cast<double>(k / 40) * 1.5;
            polys.push_back({"t" + std::to_string(k), {{x, y, 0}, {x + 1, y, 0}, {x + 1, y + 1, 0}, {x, y + 1, 0}}});
        }
        return make(polys, 2.0);
    };
    HemicubeOptions o;
    o.resolution = 64;
    o.threads = 1;
    {
        const Scene few = tiles(kRaysMinMeshPieces - 1);
        HemicubeRowProvider h(few, o);
        EXPECT_FALSE(RowDriver(few, h, FineRows::automatic, 0, o.seed).fine_rows_by_rays());
        const Scene mesh = tiles(kRaysMinMeshPieces);
        HemicubeRowProvider hm(mesh, o);
        const RowDriver d(mesh, hm, FineRows::automatic, 0, o.seed);
        EXPECT_TRUE(d.fine_rows_by_rays());
        EXPECT_EQ(d.fine_row_rays(), 8192u);
    }
    Scene obstructed = tiles(kRaysMinMeshPieces);
    obstructed.obstruction_first = static_cast<std::uint32_t>(obstructed.size() - 1);  // the last tile: an obstruction
    HemicubeRowProvider ho(obstructed, o);
    EXPECT_FALSE(RowDriver(obstructed, ho, FineRows::automatic, 0, o.seed).fine_rows_by_rays());
    EXPECT_THROW(RowDriver(obstructed, ho, FineRows::rays, 0, o.seed), InputError);
}

// Through the correction, on a sender an occluder touches: a floor and a wall, 4 × 4 patches
// each, and a two-sided fin standing on the floor near their shared edge (the floor patches it
// stands on are planned at 4 × 4). Reference: the ray caster with 4e5 rays per patch and
// another seed (object value's σ ≈ √(F/rays)/4 ≈ 2e-4). The floor→wall value with the 4 × 4
// rows ray-cast (32,768 rays: σ of the object value from those rows below 1e-4) must be within
// 5σ of the reference's noise, as the sub-hemicubes' is (tests/bench/test_sub_hemicubes.cpp).
TEST(FineRowsByRays, ThroughTheCorrectionAsCloseToTheReferenceAsSubHemicubes) {
    const Scene s = make(test::floor_wall_fin(), 0.25);
    HemicubeOptions o;
    o.resolution = 128;
    o.threads = 2;
    HemicubeRowProvider hemi(s, o);
    RowDriver driver(s, hemi, FineRows::rays, 0, o.seed);
    CorrectedRowProvider corrected(s, driver, near_field_options_for_hemicube(o.resolution));
    const double value = object_form_factors(compute_all_rows(corrected), s)[0][1];
    EXPECT_GT(corrected.stats().rows_sampled_fine, 0u);
    EXPECT_EQ(hemi.stats().fine_rows_cast, corrected.stats().rows_sampled_fine);
    RaycastOptions ro;
    ro.rays = 400000;
    ro.threads = 2;
    ro.seed = 9;
    RaycastRowProvider rays(s, ro);
    const double reference = object_form_factors(compute_all_rows(rays), s)[0][1];
    EXPECT_LT(std::abs(value - reference), 5 * 2e-4);
}

// The error estimate of a ray-cast row is the rays' noise, not the hemicube's pixels: at N = 64
// and N = 256 (the far field off, so that the analyses are the same) the cast rows are the same
// bits and so are their estimates, while the rows measured by hemicubes are estimated apart.
TEST(FineRowsByRays, ACastRowsErrorEstimateDoesNotFollowThePixels) {
    const Scene s = make(test::floor_wall_fin(), 0.25);
    std::vector<float> estimate[2];
    std::vector<std::int8_t> measure;
    for (const int k : {0, 1}) {
        HemicubeOptions o;
        o.resolution = k == 0 ? 64 : 256;
        o.threads = 2;
        HemicubeRowProvider hemi(s, o);
        RowDriver driver(s, hemi, FineRows::rays, 16384, o.seed);
        NearFieldOptions nf = near_field_options_for_hemicube(o.resolution);
        nf.far_field = NearFieldOptions::FarField::off;
        CorrectedRowProvider corrected(s, driver, nf);
        RowLedger figures;
        compute_all_rows(corrected, &figures);
        estimate[k].assign(figures.errors().begin(), figures.errors().end());
        measure.assign(figures.measures().begin(), figures.measures().end());
    }
    std::size_t cast = 0, drawn = 0;
    for (std::size_t i = 0; i < measure.size(); ++i) {
        if (measure[i] == CorrectedRowProvider::sampled_touching) {
            EXPECT_EQ(estimate[0][i], estimate[1][i]) << "row " << i;
            ++cast;
        } else if (measure[i] != CorrectedRowProvider::analytic) {
            drawn += estimate[0][i] != estimate[1][i];
        }
    }
    EXPECT_GT(cast, 0u);
    EXPECT_GT(drawn, 0u);
}

}  // namespace
}  // namespace ffcube
