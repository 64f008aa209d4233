// Adaptive meshing end to end (pipeline/adaptive.hpp) on hemicube rows: refinement of a furnace
// changes nothing, and the refined scene and its radiosity do not depend on the thread count.
#include <gtest/gtest.h>

#include <cmath>

#include <optional>

#include "ffcube/pipeline/adaptive.hpp"
#include "ffcube/scene/refine.hpp"
#include "ffcube/solver/progressive.hpp"
#include "support/scenes.hpp"

namespace ffcube {
namespace {

RowOptions small_rows(unsigned threads) {
    RowOptions o;
    o.resolution = 64;
    o.threads = threads;
    return o;
}

SolverOptions direct() {
    SolverOptions so;
    so.method = SolverMethod::Direct;
    return so;
}

TEST(Adaptive, TheFurnaceNeedsNoRefinementAndRefiningItChangesNothing) {
    // The closed unit box, every wall ρ = 0.5 and E = 1: B = E / (1 − ρ) = 2 everywhere, on any mesh.
    Scene s = test::make_scene(test::inward_box(1, 1, 1), 0.5);
    for (Material& m : s.materials) m.kd = Vec3(0.5), m.ke = Vec3(1.0);
    AdaptiveOptions ao;
    const AdaptiveResult a = solve_adaptive(s, small_rows(2), direct(), ao);
    ASSERT_EQ(a.levels.size(), 1u);
    EXPECT_EQ(a.stop, "nothing_to_refine");
    EXPECT_TRUE(a.reached_target);
    EXPECT_EQ(a.scene->size(), s.size());
    // Split every patch in 3 × 3 anyway and solve the elements: still 2. The correction closes each
    // row to 1 in double and stores it in float (relative rounding 6e-8 per value, at most about
    // 1e-7 on a row's sum s). B = E / (1 − ρ s) moves by ρ E / (1 − ρ)² = 2 per unit of s, so
    // |B − 2| ≤ 2e-7; 1e-6 leaves room for the LU's rounding.
    const RefinedScene fine = refine_patches(s, std::vector<std::uint32_t>(s.size(), 3));
    RowSource rows = make_row_source(fine.scene, small_rows(2));
    const SolveResult r = solve_radiosity(fine.scene, rows.provider(), direct());
    ASSERT_EQ(r.radiosity.size(), 9 * s.size());
    for (const Vec3& b : r.radiosity) {
        EXPECT_NEAR(b.r, 2.0, 1e-6);
        EXPECT_NEAR(b.b, 2.0, 1e-6);
    }
    for (const Vec3& b : a.result.radiosity) EXPECT_NEAR(b.g, 2.0, 1e-6);
}

// A floor under a square light, a square occluder between them: a shadow with a penumbra.
Scene shadow_scene() {
    Scene s = test::make_scene({test::square_z("floor", 0.0, true, 2.0, Vec3(-1, -1, 0)),
                                test::square_z("occluder", 0.5, true, 0.5, Vec3(-0.25, -0.25, 0)),
                                test::square_z("light", 1.0, false, 0.5, Vec3(-0.5, -0.25, 0))},
                               0.5);
    s.materials.push_back(Material{"lamp", Vec3(0.0), Vec3(10.0)});
    for (Patch& p : s.patches)
        if (s.objects[p.object] == "light") p.material = static_cast<std::uint32_t>(s.materials.size() - 1);
    return s;
}

TEST(Adaptive, SameRefinementAndRadiosityOnOneThreadAndTwo) {
    const Scene s = shadow_scene();
    AdaptiveOptions ao;
    ao.target_error = 1e-3;
    ao.max_levels = 2;
    const AdaptiveResult one = solve_adaptive(s, small_rows(1), direct(), ao);
    const AdaptiveResult two = solve_adaptive(s, small_rows(2), direct(), ao);
    EXPECT_GT(one.scene->size(), s.size());
    ASSERT_EQ(one.scene->size(), two.scene->size());
    EXPECT_EQ(one.origin, two.origin);
    EXPECT_EQ(one.scene->fingerprint, two.scene->fingerprint);
    ASSERT_EQ(one.result.radiosity.size(), two.result.radiosity.size());
    for (std::size_t i = 0; i < one.result.radiosity.size(); ++i) EXPECT_EQ(one.result.radiosity[i], two.result.radiosity[i]) << i;
    // A result moved into place (cmd_solve assigns it into an optional) keeps its last level's rows
    // usable: they refer to the scene it holds, not to the moved-from one. Every row they give
    // equals a fresh source's on that scene (the same options: bitwise the same rows).
    std::optional<AdaptiveResult> held;
    held = solve_adaptive(s, small_rows(2), direct(), ao);
    RowSource fresh = make_row_source(*held->scene, small_rows(2));
    const CsrMatrix kept = compute_all_rows(held->rows.provider());
    const CsrMatrix again = compute_all_rows(fresh.provider());
    ASSERT_EQ(kept.size(), held->scene->size());
    ASSERT_EQ(kept.nnz(), again.nnz());
    for (std::uint32_t i = 0; i < kept.size(); ++i) EXPECT_EQ(kept.row(i).sum(), again.row(i).sum()) << i;
    // The shadow is on the floor: the floor is where the elements went.
    std::size_t floor_elements = 0;
    for (const Patch& p : one.scene->patches) floor_elements += s.objects[p.object] == "floor" ? 1 : 0;
    std::size_t floor_patches = 0;
    for (const Patch& p : s.patches) floor_patches += s.objects[p.object] == "floor" ? 1 : 0;
    EXPECT_GT(floor_elements, floor_patches);
}

TEST(Adaptive, KeptWorkersGiveTheSameBitsAsWorkersRestartedPerLevel) {
    // The shadow scene above; rows are not carried over, so every row of level 1 comes from the
    // workers that level 0 started (kept) or from new ones (restarted). Forked workers (the
    // default); workers on threads are checked in tests/gl (HemicubeWorkers.SetScene...), which
    // keeps this test within its time.
    const Scene s = shadow_scene();
    {
        const RowOptions ro = small_rows(2);
        AdaptiveOptions ao;
        ao.target_error = 1e-3;
        ao.max_levels = 1;  // level 0, then one refined level on the kept (or new) workers
        ao.reuse_rows = false;
        ao.keep_workers = true;
        AdaptiveResult kept = solve_adaptive(s, ro, direct(), ao);
        // The last level's rows, entry by entry, from the kept workers; then those workers end
        // (their pool's threads would keep the next solve from forking).
        ASSERT_NE(kept.rows.hemicube(), nullptr);
        const std::string kept_workers = kept.rows.hemicube()->workers();
        const CsrMatrix fa = compute_all_rows(kept.rows.provider());
        kept.rows = RowSource{};
        ao.keep_workers = false;
        AdaptiveResult restarted = solve_adaptive(s, ro, direct(), ao);
        ASSERT_GE(kept.levels.size(), 2u) << "the test needs a refined level";
        ASSERT_EQ(kept.levels.size(), restarted.levels.size());
        for (std::size_t l = 0; l < kept.levels.size(); ++l) {
            EXPECT_EQ(kept.levels[l].elements, restarted.levels[l].elements) << l;
            EXPECT_EQ(kept.levels[l].objects, restarted.levels[l].objects) << l;
        }
        ASSERT_EQ(kept.result.radiosity.size(), restarted.result.radiosity.size());
        for (std::size_t i = 0; i < kept.result.radiosity.size(); ++i)
            EXPECT_EQ(kept.result.radiosity[i], restarted.result.radiosity[i]) << i;
        // Forked workers when this process has made no GL context: so under ctest (one process per
        // test); run after other tests in one process, both sides fall back to threads alike.
        EXPECT_EQ(kept_workers, restarted.rows.hemicube()->workers());
        const CsrMatrix fb = compute_all_rows(restarted.rows.provider());
        ASSERT_EQ(fa.size(), kept.scene->size());
        ASSERT_EQ(fa.nnz(), fb.nnz());
        for (std::uint32_t i = 0; i < fa.size(); ++i) {
            const auto ra = fa.row(i), rb = fb.row(i);
            ASSERT_EQ(ra.col.size(), rb.col.size()) << i;
            for (std::size_t k = 0; k < ra.col.size(); ++k) {
                EXPECT_EQ(ra.col[k], rb.col[k]) << i;
                EXPECT_EQ(ra.val[k], rb.val[k]) << i;
            }
        }
    }
}

// AdaptiveRun driven from outside, level by level, as the viewer drives it (its own progressive
// solver in small steps, finish_level, next_level), gives what solve_adaptive gives with the
// shooting solve: the same levels, elements and radiosity, bit for bit. Shooting is deterministic
// however the shots are split into steps (solver/progressive.hpp), and solve_radiosity's shooting
// runs the same ProgressiveSolver unless it switches to GMRES on a stiff scene, which ρ = 0.5
// here does not need (checked on the last level's result: stiffness.action "none").
TEST(Adaptive, RunDrivenLevelByLevelEqualsSolveAdaptive) {
    const Scene s = shadow_scene();
    SolverOptions shoot;
    shoot.method = SolverMethod::Shoot;
    shoot.tolerance = 1e-6;
    AdaptiveOptions ao;
    ao.target_error = 1e-3;
    ao.max_levels = 2;
    const AdaptiveResult whole = solve_adaptive(s, small_rows(2), shoot, ao);
    ASSERT_GE(whole.levels.size(), 2u) << "the test needs a refined level";
    EXPECT_EQ(whole.result.stiffness.action, "none");

    AdaptiveRun run(s, small_rows(2), shoot, ao);
    std::vector<std::size_t> sizes;
    for (;;) {
        EXPECT_EQ(run.level(), sizes.size());
        sizes.push_back(run.scene().size());
        ProgressiveSolver solver(run.scene(), run.provider(), shoot);
        while (solver.step(StepBudget{.max_shots = 7}) == StopReason::Running) {
        }
        run.finish_level(solver.result());
        // Until next_level the level's scene and rows stay as they were (a viewer still shows them).
        EXPECT_EQ(run.scene().size(), sizes.back());
        EXPECT_EQ(run.provider().size(), sizes.back());
        if (run.done()) break;
        run.next_level();
    }
    const AdaptiveResult stepped = run.take_result();
    ASSERT_EQ(stepped.levels.size(), whole.levels.size());
    for (std::size_t l = 0; l < whole.levels.size(); ++l) {
        EXPECT_EQ(sizes[l], whole.levels[l].elements) << l;
        EXPECT_EQ(stepped.levels[l].elements, whole.levels[l].elements) << l;
        EXPECT_EQ(stepped.levels[l].refined, whole.levels[l].refined) << l;
        EXPECT_EQ(stepped.levels[l].rows_computed, whole.levels[l].rows_computed) << l;
        EXPECT_EQ(stepped.levels[l].rows_reused, whole.levels[l].rows_reused) << l;
        EXPECT_EQ(stepped.levels[l].objects, whole.levels[l].objects) << l;
    }
    EXPECT_EQ(stepped.stop, whole.stop);
    EXPECT_EQ(stepped.origin, whole.origin);
    EXPECT_EQ(stepped.max_relative_error, whole.max_relative_error);
    ASSERT_EQ(stepped.result.radiosity.size(), whole.result.radiosity.size());
    for (std::size_t i = 0; i < whole.result.radiosity.size(); ++i)
        EXPECT_EQ(stepped.result.radiosity[i], whole.result.radiosity[i]) << i;
}

}  // namespace
}  // namespace ffcube
