// Progressive refinement: furnace, emitters, overshooting, divergence, the row cache, determinism
// and the stepping API. Rows come from fixtures.hpp (exact double rows, analytic where possible).
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <string>

#include "ffcube/core/error.hpp"
#include "ffcube/solver/progressive.hpp"
#include "ffcube/solver/row_cache.hpp"
#include "ffcube/solver/solver.hpp"
#include "fixtures.hpp"

namespace ffcube {
namespace {

using namespace ffcube::test;

constexpr double kEps = 1.1102230246251565e-16;  // unit roundoff of double

Scene furnace(double rho, double emit) {
    return make_scene(std::vector<double>(6, 1.0), {grey("box", rho, emit)}, std::vector<std::uint32_t>(6, 0));
}

bool bitwise_equal(std::span<const Vec3> a, std::span<const Vec3> b) {
    return a.size() == b.size() && std::memcmp(a.data(), b.data(), a.size() * sizeof(Vec3)) == 0;
}

double max_row_sum_error(const std::vector<SparseRow>& rows) {
    double worst = 0.0;
    for (const SparseRow& r : rows) worst = std::max(worst, std::abs(r.sum() - 1.0));
    return worst;
}

class Furnace : public ::testing::TestWithParam<double> {};

TEST_P(Furnace, ClosedCubeGivesEOverOneMinusRho) {
    const double rho = GetParam();
    const Scene scene = furnace(rho, 1.0);
    ExactRowProvider provider(cube_rows());
    SolverOptions o;
    o.tolerance = 1e-10;
    o.max_iterations = 10'000'000;
    const SolveResult r = solve_radiosity(scene, provider, o);
    ASSERT_EQ(r.stop, StopReason::Converged) << "after " << r.shots << " shots";
    RecordProperty("shots", std::to_string(r.shots));

    // Error budget, relative to B* = 1/(1 − ρ):
    //  - tolerance: the state obeys B* − B = (I − K)⁻¹ K ΔB with ‖K‖_∞ = ρ × (column sum of F = 1 for
    //    the symmetric cube), so |B − B*| ≤ ρ/(1 − ρ) ‖ΔB‖_∞ ≤ ρ/(1 − ρ) × τ × (emitted = 6) / (A = 1):
    //    relative 6τρ;
    //  - rows: the closed forms sum to 1 only up to rounding s − 1 = δ; the exact answer for the rows
    //    at hand is 1/(1 − ρs), relative ρ|δ|/(1 − ρ) away;
    //  - rounding: each B_j is a sum of at most `shots` positive terms, relative error ≤ shots × ε.
    const double delta = max_row_sum_error(provider.rows());
    const double bound = 6 * o.tolerance * rho + rho * delta / (1 - rho) + double(r.shots) * kEps;
    const double expected = 1.0 / (1.0 - rho);
    for (const Vec3& b : r.radiosity)
        for (int c = 0; c < 3; ++c) {
            EXPECT_NEAR(b[c] / expected, 1.0, bound);
            // Shooting without overshoot only adds positive energy: B approaches B* from below.
            EXPECT_LE(b[c], expected * (1 + bound));
        }
    // Closed box: escaped = Σ shots (1 − rowsum) × power, and the power shot per face sums to its
    // shot radiosity ≤ B*: |escaped| ≤ δ × 6 B*, doubled for the rounding of the row sum itself.
    for (int c = 0; c < 3; ++c) EXPECT_LE(std::abs(r.energy.escaped[c]), delta * 6 * expected * 2);
    EXPECT_EQ(r.cache.patches_without_row, 0u);
    EXPECT_EQ(r.cache.rows_computed, 6u);
}

INSTANTIATE_TEST_SUITE_P(Rho, Furnace, ::testing::Values(0.5, 0.9, 0.99, 0.999));

TEST(Progressive, ZeroReflectanceShootsEachEmitterOnce) {
    const Scene scene = furnace(0.0, 1.0);
    ExactRowProvider provider(cube_rows());
    const SolveResult r = solve_radiosity(scene, provider, SolverOptions{});
    EXPECT_EQ(r.stop, StopReason::Converged);
    EXPECT_EQ(r.shots, 6u);
    EXPECT_EQ(r.unshot_fraction, 0.0);  // ρ = 0: nothing is ever reflected back
    for (const Vec3& b : r.radiosity) EXPECT_EQ(b, Vec3(1.0));
}

TEST(Progressive, OnlyShootersGetRows) {
    // One lamp (face 0) with ρ = 0; every other face black: only the lamp ever has unshot energy.
    const Scene scene = make_scene(std::vector<double>(6, 1.0), {grey("lamp", 0.0, 2.0), grey("black", 0.0, 0.0)},
                                   {0, 1, 1, 1, 1, 1});
    ExactRowProvider provider(cube_rows());
    const SolveResult r = solve_radiosity(scene, provider, SolverOptions{});
    EXPECT_EQ(r.shots, 1u);
    EXPECT_EQ(r.radiosity[0], Vec3(2.0));
    for (std::uint32_t i = 1; i < 6; ++i) {
        EXPECT_EQ(r.radiosity[i], Vec3(0.0));
        EXPECT_EQ(provider.requests(i), 0u);
    }
    EXPECT_EQ(r.cache.rows_computed, 1u);
    EXPECT_EQ(r.cache.patches_without_row, 5u);
}

TEST(Progressive, BlackPatchesNeverNeedARow) {
    // Faces 2 and 3 absorb everything (ρ = 0, E = 0): they receive but never hold unshot energy.
    const Scene scene = make_scene(std::vector<double>(6, 1.0),
                                   {grey("lamp", 0.5, 1.0), grey("wall", 0.5, 0.0), grey("black", 0.0, 0.0)},
                                   {0, 1, 2, 2, 1, 1});
    ExactRowProvider provider(cube_rows());
    SolverOptions o;
    o.tolerance = 1e-8;
    const SolveResult r = solve_radiosity(scene, provider, o);
    EXPECT_EQ(r.stop, StopReason::Converged);
    EXPECT_EQ(provider.requests(2), 0u);
    EXPECT_EQ(provider.requests(3), 0u);
    EXPECT_EQ(r.cache.patches_without_row, 2u);
    EXPECT_EQ(r.cache.rows_computed, 4u);
    EXPECT_EQ(r.cache.rows_reused, r.shots - 4);
    EXPECT_EQ(r.cache.rows_evicted, 0u);
    EXPECT_EQ(provider.total_requests(), 4u);
}

TEST(Progressive, NoEmittersIsNothingToDo) {
    const Scene scene = furnace(0.5, 0.0);
    ExactRowProvider provider(cube_rows());
    ProgressiveSolver solver(scene, provider, SolverOptions{});
    EXPECT_EQ(solver.status(), StopReason::NothingToDo);
    EXPECT_EQ(solver.step({}), StopReason::NothingToDo);
    const SolveResult r = solver.result();
    EXPECT_EQ(r.stop, StopReason::NothingToDo);
    EXPECT_EQ(r.shots, 0u);
    ASSERT_EQ(r.warnings.size(), 1u);
    EXPECT_NE(r.warnings[0].find("no patch emits"), std::string::npos);
    for (const Vec3& b : r.radiosity) EXPECT_EQ(b, Vec3(0.0));
    EXPECT_EQ(provider.total_requests(), 0u);
}

// A ring of 40 patches, ρ = 0.99, one lamp: light must diffuse patch by patch around the ring, the
// stiff case where Cohen's shooting needs many shots.
struct Ring {
    Scene scene;
    std::vector<SparseRow> rows;
};
Ring stiff_ring() {
    const std::uint32_t n = 40;
    std::vector<std::uint32_t> mat(n, 1);
    mat[0] = 0;
    return {make_scene(std::vector<double>(n, 1.0), {grey("lamp", 0.99, 1.0), grey("wall", 0.99, 0.0)}, mat),
            ring_rows(n)};
}

TEST(Progressive, OvershootingConvergesToTheSameAnswerWithFewerRows) {
    const Ring ring = stiff_ring();
    ExactRowProvider direct_rows(ring.rows);
    SolverOptions d;
    d.method = SolverMethod::Direct;
    const SolveResult reference = solve_radiosity(ring.scene, direct_rows, d);

    std::uint64_t rows_plain = 0;
    for (double omega : {1.0, kDefaultOvershoot, 1.5}) {
        ExactRowProvider provider(ring.rows);
        SolverOptions o;
        o.tolerance = 1e-8;
        o.overshoot = omega;
        o.row_cache_mb = 0;  // every shot asks the provider: rows computed = shots
        o.max_iterations = 1'000'000;
        o.stiff_switch = false;  // shooting itself, not the default's GMRES finish (test_stiff.cpp)
        const SolveResult r = solve_radiosity(ring.scene, provider, o);
        ASSERT_EQ(r.stop, StopReason::Converged) << "omega " << omega;
        EXPECT_EQ(r.cache.rows_computed, r.shots);
        // B* − B = (I − K)⁻¹ K ΔB (any sign of ΔB), ‖K‖_∞ = ρ (symmetric ring, column sums 1), so
        // |B − B*| ≤ ρ/(1 − ρ) × τ × (emitted = 1) / (A = 1) = 99 τ; the direct solution's own error,
        // cond × ε × |B| ≈ 200 × 1.1e-16 × 3, is far below that.
        EXPECT_LE(max_abs_diff(r.radiosity, reference.radiosity), 99 * o.tolerance) << "omega " << omega;
        if (omega == 1.0)
            rows_plain = r.cache.rows_computed;
        else
            EXPECT_LT(r.cache.rows_computed, rows_plain) << "omega " << omega;
        RecordProperty("rows_omega_" + std::to_string(omega), std::to_string(r.cache.rows_computed));
    }
}

TEST(Progressive, OvershootingOnOneWayRowsIsStoppedAsDiverged) {
    // Rows that pass the stiffness check (ρ × rowsum = 0.99) but are far from reciprocal: each patch
    // of a ring sends 90% of its light forward and 10% back. Over-relaxation relies on reciprocity
    // (docs/solvers.md); here ω = 1.5 makes the unshot energy grow geometrically, and the solve must
    // stop with its reason rather than loop or overflow.
    const std::uint32_t n = 10;
    std::vector<SparseRow> rows(n);
    for (std::uint32_t i = 0; i < n; ++i) {
        const std::uint32_t back = (i + n - 1) % n, fwd = (i + 1) % n;
        rows[i].col = {std::min(back, fwd), std::max(back, fwd)};
        rows[i].val = back < fwd ? std::vector<double>{0.1, 0.9} : std::vector<double>{0.9, 0.1};
    }
    std::vector<std::uint32_t> mat(n, 1);
    mat[0] = 0;
    const Scene scene =
        make_scene(std::vector<double>(n, 1.0), {grey("lamp", 0.99, 1.0), grey("wall", 0.99, 0.0)}, mat);
    SolverOptions o;
    o.overshoot = 1.5;
    ExactRowProvider provider(rows);
    const SolveResult r = solve_radiosity(scene, provider, o);
    EXPECT_EQ(r.stop, StopReason::Diverged);
    EXPECT_GT(r.unshot_fraction, 1000.0);
    EXPECT_FALSE(r.warnings.empty());
    // Plain shooting (ω = 1) on the same rows converges: K ≥ 0 with ‖ρF‖_∞ < 1.
    o.overshoot = 1.0;
    ExactRowProvider provider2(rows);
    EXPECT_EQ(solve_radiosity(scene, provider2, o).stop, StopReason::Converged);
}

TEST(Progressive, SmallCacheCountsAndSameResult) {
    const std::uint32_t n = 12;
    std::vector<std::uint32_t> mat(n, 1);
    mat[0] = 0;
    const Scene scene =
        make_scene(std::vector<double>(n, 1.0), {grey("lamp", 0.9, 1.0), grey("wall", 0.9, 0.0)}, mat);
    SolverOptions o;
    o.tolerance = 1e-8;

    ExactRowProvider unbounded_rows(ring_rows(n));
    const SolveResult unbounded = solve_radiosity(scene, unbounded_rows, o);
    const std::uint64_t distinct = n - unbounded.cache.patches_without_row;
    EXPECT_EQ(unbounded.cache.rows_computed, distinct);
    EXPECT_EQ(unbounded.cache.rows_reused, unbounded.shots - distinct);
    EXPECT_EQ(unbounded.cache.rows_evicted, 0u);
    EXPECT_EQ(unbounded.cache.rows_recomputed, 0u);
    EXPECT_EQ(unbounded_rows.total_requests(), distinct);

    // Room for two rows of the ring (2 non-zeros each), not three.
    o.row_cache_mb = 2.5 * double(RowCache::cost(2)) / 1048576.0;
    ExactRowProvider small_rows(ring_rows(n));
    const SolveResult small = solve_radiosity(scene, small_rows, o);
    EXPECT_EQ(small.shots, unbounded.shots);
    EXPECT_TRUE(bitwise_equal(small.radiosity, unbounded.radiosity));
    EXPECT_EQ(small.cache.rows_computed + small.cache.rows_reused, small.shots);
    EXPECT_EQ(small.cache.rows_computed, small_rows.total_requests());
    EXPECT_GT(small.cache.rows_computed, distinct);  // the two-row cache cannot hold the working set
    // Every computed row was inserted; the cache ends full with 2 rows, so all others were evicted.
    EXPECT_EQ(small.cache.rows_evicted, small.cache.rows_computed - 2);
    EXPECT_EQ(small.cache.rows_recomputed, small.cache.rows_computed - distinct);
    EXPECT_EQ(small.cache.patches_without_row, unbounded.cache.patches_without_row);
    EXPECT_LE(small.cache.peak_bytes, small.cache.capacity_bytes);

    o.row_cache_mb = 0;
    ExactRowProvider no_rows(ring_rows(n));
    const SolveResult none = solve_radiosity(scene, no_rows, o);
    EXPECT_TRUE(bitwise_equal(none.radiosity, unbounded.radiosity));
    EXPECT_EQ(none.cache.rows_computed, none.shots);
    EXPECT_EQ(none.cache.rows_reused, 0u);
    EXPECT_EQ(none.cache.rows_evicted, 0u);
}

// A 30-patch open scene with coloured materials: the general case for determinism and batches.
Scene coloured_scene(const std::vector<double>& areas) {
    std::vector<std::uint32_t> mat(areas.size());
    for (std::uint32_t i = 0; i < mat.size(); ++i) mat[i] = i % 3;
    mat[4] = 3;
    mat[17] = 4;
    return make_scene(areas,
                      {Material{"red", Vec3(0.8, 0.3, 0.2), Vec3(0.0)}, Material{"green", Vec3(0.2, 0.7, 0.3), Vec3(0.0)},
                       Material{"white", Vec3(0.9), Vec3(0.0)}, Material{"lamp", Vec3(0.5), Vec3(10, 9, 7)},
                       Material{"lamp2", Vec3(0.1), Vec3(1, 2, 3)}},
                      mat);
}

TEST(Progressive, DeterministicBitForBit) {
    const RandomScene rs = random_reciprocal(30, 0.95, 11);
    const Scene scene = coloured_scene(rs.areas);
    for (std::uint32_t batch : {1u, 4u}) {
        SolverOptions o;
        o.tolerance = 1e-9;
        o.batch = batch;
        ExactRowProvider p1(rs.rows), p2(rs.rows), p3(rs.rows);
        const SolveResult a = solve_radiosity(scene, p1, o);
        const SolveResult b = solve_radiosity(scene, p2, o);
        EXPECT_TRUE(bitwise_equal(a.radiosity, b.radiosity)) << "batch " << batch;
        EXPECT_EQ(a.shots, b.shots);
        // Split into steps of 7 shots (whole batches): the same shots in the same order.
        ProgressiveSolver stepped(scene, p3, o);
        while (stepped.step({.max_shots = 7}) == StopReason::Running) {
        }
        EXPECT_TRUE(bitwise_equal(stepped.radiosity(), a.radiosity)) << "batch " << batch;
        EXPECT_EQ(stepped.shots(), a.shots);
        if (batch > 1) {
            EXPECT_LT(p1.calls(), a.shots);  // several rows per provider call
        }
    }
}

TEST(Progressive, BatchesConvergeToTheSameAnswer) {
    const RandomScene rs = random_reciprocal(30, 0.95, 11);
    const Scene scene = coloured_scene(rs.areas);
    SolverOptions o;
    o.tolerance = 1e-11;
    ExactRowProvider p1(rs.rows), p4(rs.rows);
    const SolveResult one = solve_radiosity(scene, p1, o);
    o.batch = 4;
    const SolveResult four = solve_radiosity(scene, p4, o);
    ASSERT_EQ(one.stop, StopReason::Converged);
    ASSERT_EQ(four.stop, StopReason::Converged);
    // Both within (q/(1 − q)) × τ × emitted / A_min of B*, q = max ρ rowsum ≤ 0.9 × 0.95 = 0.855
    // (‖K‖_∞ = q for reciprocal rows), emitted ≤ 26 × 3 + 6 × 3 (lamps' Ke sums × A < 3), A_min ≥ 1:
    // |B − B*| ≤ 5.9 × 1e-11 × 96 ≈ 5.7e-9 each, so they differ by at most twice that.
    EXPECT_LE(max_abs_diff(one.radiosity, four.radiosity), 1.2e-8);
}

TEST(Progressive, SteppingResetAndCacheKept) {
    const Ring ring = stiff_ring();
    ExactRowProvider provider(ring.rows);
    SolverOptions o;
    o.tolerance = 1e-3;
    ProgressiveSolver solver(ring.scene, provider, o);
    EXPECT_EQ(solver.shots(), 0u);
    EXPECT_EQ(solver.unshot_fraction(), 1.0);
    EXPECT_EQ(solver.step({.max_shots = 1}), StopReason::Running);
    EXPECT_EQ(solver.shots(), 1u);
    EXPECT_EQ(solver.step({.seconds = 0.0}), StopReason::Running);  // a step always advances
    EXPECT_EQ(solver.shots(), 2u);
    EXPECT_EQ(solver.run(), StopReason::Converged);
    const std::vector<Vec3> first(solver.radiosity().begin(), solver.radiosity().end());
    const RowCacheStats before = solver.cache_stats();

    solver.reset();
    EXPECT_EQ(solver.shots(), 0u);
    EXPECT_EQ(solver.status(), StopReason::Running);
    EXPECT_EQ(solver.unshot_fraction(), 1.0);
    EXPECT_EQ(solver.radiosity()[0], Vec3(1.0));
    EXPECT_EQ(solver.radiosity()[1], Vec3(0.0));
    EXPECT_EQ(solver.run(), StopReason::Converged);
    EXPECT_TRUE(bitwise_equal(solver.radiosity(), first));
    const RowCacheStats after = solver.cache_stats();
    EXPECT_EQ(after.rows_computed, before.rows_computed);  // every row came from the cache
    EXPECT_EQ(after.rows_reused, before.rows_reused + solver.shots());
}

TEST(Progressive, IterationLimitIsExactEvenWithBatches) {
    const Ring ring = stiff_ring();
    for (std::uint32_t batch : {1u, 4u}) {
        ExactRowProvider provider(ring.rows);
        SolverOptions o;
        o.max_iterations = 5;
        o.batch = batch;
        const SolveResult r = solve_radiosity(ring.scene, provider, o);
        EXPECT_EQ(r.stop, StopReason::IterationLimit);
        EXPECT_EQ(r.shots, 5u);
        EXPECT_EQ(r.iterations, 5u);
    }
}

TEST(Progressive, AmbientMakesTheFurnaceExactAtTheStart) {
    // Uniform closed furnace before any shot: ambient = (Σ A E / Σ A) / (1 − ρ̄) = E/(1 − ρ), and
    // B + ρ × ambient = E + ρE/(1 − ρ) = E/(1 − ρ), the exact answer up to four roundings of
    // numbers ≤ 10 (a division, a product, a sum, the check's product): 4 × 10ε absolute.
    const double rho = 0.9;
    const Scene scene = furnace(rho, 1.0);
    ExactRowProvider provider(cube_rows());
    SolverOptions o;
    o.tolerance = 1e-10;
    ProgressiveSolver solver(scene, provider, o);
    const std::vector<Vec3> shown = display_radiosity(scene, solver.radiosity(), solver.ambient());
    for (const Vec3& b : shown) EXPECT_NEAR(b.x * (1 - rho), 1.0, 4 * kEps * 10);
    EXPECT_EQ(solver.radiosity()[0], Vec3(1.0));  // the ambient term never enters B
    solver.run();
    // At the end the ambient is what is left unshot: ≤ τ × emitted / Σ A / (1 − ρ) per channel.
    const Vec3 amb = solver.ambient();
    for (int c = 0; c < 3; ++c) EXPECT_LE(std::abs(amb[c]), o.tolerance * 6 / 6 / (1 - rho));
}

TEST(Progressive, EnergyBalanceOfAnOpenScene) {
    const RandomScene rs = random_reciprocal(30, 0.95, 5);
    const Scene scene = coloured_scene(rs.areas);
    SolverOptions o;
    o.tolerance = 1e-10;
    ExactRowProvider p(rs.rows), pd(rs.rows);
    const SolveResult r = solve_radiosity(scene, p, o);
    SolverOptions d;
    d.method = SolverMethod::Direct;
    const SolveResult exact = solve_radiosity(scene, pd, d);
    const EnergyBalance& e = r.energy;
    // The invariant is checked during the solve to 1e-5 (a failure throws); here to its rounding
    // bound 3 S ε of the turnover (progressive.cpp), S ≤ shots × 30 non-zeros processed.
    const double rounding = 3.0 * double(r.shots) * 30 * kEps;
    EXPECT_LE(e.relative_error, rounding);
    const double emitted_total = e.emitted.x + e.emitted.y + e.emitted.z;
    // The turnover (all power shot) is at most emitted / (1 − q), q = max ρ rowsum ≤ 0.9 × 0.95.
    const double turnover = emitted_total / (1 - 0.9 * 0.95);
    for (int c = 0; c < 3; ++c) {
        EXPECT_GT(e.escaped[c], 0.0);  // the scene is open: rows sum to at most 0.95
        // |unshot| ≤ Σ A |ΔB| ≤ τ × emitted (all channels).
        EXPECT_LE(std::abs(e.unshot[c]), o.tolerance * emitted_total);
        // What is still unshot would be absorbed or escape later: the direct solution's balance
        // differs from ours by at most that, plus rounding.
        EXPECT_NEAR(e.absorbed[c], exact.energy.absorbed[c], o.tolerance * emitted_total + rounding * turnover);
        EXPECT_NEAR(e.escaped[c], exact.energy.escaped[c], o.tolerance * emitted_total + rounding * turnover);
    }
}

TEST(Progressive, HistoryAndProgress) {
    const Ring ring = stiff_ring();
    ExactRowProvider provider(ring.rows);
    SolverOptions o;
    o.tolerance = 1e-4;
    o.history_capacity = 16;
    o.stiff_switch = false;  // one progress call per shot: plain shooting to the end
    std::uint64_t calls = 0;
    double last = -1.0;
    o.progress = [&](const SolveProgress& p) {
        ++calls;
        EXPECT_EQ(p.iterations, calls);
        last = p.unshot_fraction;
    };
    const SolveResult r = solve_radiosity(ring.scene, provider, o);
    EXPECT_EQ(calls, r.shots);
    EXPECT_EQ(last, r.unshot_fraction);
    ASSERT_LE(r.history.size(), 16u);
    ASSERT_GE(r.history.size(), 2u);
    EXPECT_EQ(r.history.front().unshot_fraction, 1.0);
    EXPECT_EQ(r.history.back().unshot_fraction, r.unshot_fraction);
    for (std::size_t k = 1; k < r.history.size(); ++k) EXPECT_GE(r.history[k].seconds, r.history[k - 1].seconds);
}

TEST(Progressive, RowBreakingTheStiffnessRuleIsRefusedWhenItArrives) {
    // Kd = 0.999 passes the material rule, but these rows sum to 1.002 (a coarse hemicube): ρ × 1.002 ≥ 1.
    std::vector<SparseRow> rows = cube_rows();
    for (SparseRow& r : rows)
        for (double& v : r.val) v *= 1.002;
    const Scene scene = furnace(0.999, 1.0);
    ExactRowProvider provider(rows);
    ProgressiveSolver solver(scene, provider, SolverOptions{});
    try {
        solver.step({.max_shots = 1});
        FAIL() << "expected InputError";
    } catch (const InputError& e) {
        EXPECT_NE(std::string(e.what()).find("no steady state"), std::string::npos) << e.what();
    }
    EXPECT_EQ(solver.shots(), 0u);  // the state is that of before the refused row
}

}  // namespace
}  // namespace ffcube
