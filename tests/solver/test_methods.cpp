// All four methods on the same rows; refusals; options; the output helpers.
#include <gtest/gtest.h>

#include <cmath>
#include <string>

#include "ffcube/core/error.hpp"
#include "ffcube/solver/solver.hpp"
#include "fixtures.hpp"

namespace ffcube {
namespace {

using namespace ffcube::test;

constexpr SolverMethod kAll[] = {SolverMethod::Shoot, SolverMethod::Jacobi, SolverMethod::GaussSeidel,
                                 SolverMethod::Direct};

// 24 patches, reciprocal rows summing to at most 0.97, coloured materials, two coloured lamps.
struct Case {
    RandomScene rs;
    Scene scene;
};
Case mixed_case() {
    Case c{random_reciprocal(24, 0.97, 42), {}};
    std::vector<std::uint32_t> mat(24);
    for (std::uint32_t i = 0; i < mat.size(); ++i) mat[i] = i % 3;
    mat[3] = 3;
    mat[20] = 4;
    c.scene = make_scene(c.rs.areas,
                         {Material{"a", Vec3(0.8, 0.5, 0.3), Vec3(0.0)}, Material{"b", Vec3(0.6, 0.7, 0.9), Vec3(0.0)},
                          Material{"c", Vec3(0.9), Vec3(0.0)}, Material{"lamp", Vec3(0.4), Vec3(5, 4, 3)},
                          Material{"lamp2", Vec3(0.2, 0.0, 0.6), Vec3(1, 2, 3)}},
                         mat);
    return c;
}

TEST(Methods, AllFourAgreeOnTheSameRows) {
    const Case c = mixed_case();
    SolverOptions o;
    o.tolerance = 1e-13;
    std::vector<SolveResult> results;
    for (SolverMethod m : kAll) {
        ExactRowProvider provider(c.rs.rows);
        o.method = m;
        results.push_back(solve_radiosity(c.scene, provider, o));
        ASSERT_EQ(results.back().stop, StopReason::Converged) << to_string(m);
        EXPECT_EQ(results.back().method, m);
    }
    const std::vector<Vec3>& exact = results[3].radiosity;  // direct
    // Error bound of each iterative method against B*:
    //   gathering: |B − B*|_∞ ≤ ‖(I − ρF)⁻¹‖_∞ max|r_i| ≤ 1/(1 − q) × τ × emitted / A_min;
    //   shooting:  |B − B*|_∞ ≤ ‖(I − K)⁻¹K‖_∞ ‖ΔB‖_∞ ≤ q/(1 − q) × τ × emitted / A_min
    //   (‖K‖_∞ = max_j ρ_j Σ_i F_ij A_i / A_j = q for reciprocal rows),
    // with q = max_i,c ρ_ic rowsum_i ≤ 0.9 × 0.97. The direct solve is backward stable: its error is
    // about N × cond × ε ≈ 24 × 8 × 1.1e-16, negligible. Computed from the data below, the bound is
    // far under the 1e-8 relative agreement asked of the methods.
    double q = 0.0, a_min = INFINITY, emitted = 0.0;
    for (std::size_t i = 0; i < c.scene.size(); ++i) {
        const Material& m = c.scene.materials[c.scene.patches[i].material];
        const double s = c.rs.rows[i].sum();
        q = std::max({q, m.kd.x * s, m.kd.y * s, m.kd.z * s});
        a_min = std::min(a_min, c.scene.patches[i].area);
        emitted += (m.ke.x + m.ke.y + m.ke.z) * c.scene.patches[i].area;
    }
    const double bound = o.tolerance * emitted / a_min / (1 - q) / max_abs(exact);
    ASSERT_LT(bound, 1e-9);
    for (int k = 0; k < 3; ++k) {
        const double rel = max_abs_diff(results[k].radiosity, exact) / max_abs(exact);
        EXPECT_LE(rel, 1e-8) << to_string(kAll[k]);
        // Plus rounding: a shot B_j is a sum of at most `shots` terms (relative ≤ shots × ε); a swept
        // B_i is recomputed each sweep from at most 24 terms (≤ 24ε).
        const double rounding = double(results[k].shots + 24) * 1.1102230246251565e-16;
        EXPECT_LE(rel, bound + rounding) << to_string(kAll[k]);
    }
    // Jacobi's residual obeys r_{k+1} = ρF r_k; in the area-weighted 1-norm, with reciprocity,
    // Σ_i A_i ρ_i F_ij = A_j Σ_i ρ_i F_ji ≤ A_j q', q' = max ρ × max rowsum, so the residual fraction
    // (≤ q' at the start, r_0 = ρFE) is ≤ q'^(k+1) after k sweeps: at most ⌈log τ / log q'⌉ sweeps.
    double rho_max = 0.0, s_max = 0.0;
    for (std::size_t i = 0; i < c.scene.size(); ++i) {
        const Vec3 kd = c.scene.materials[c.scene.patches[i].material].kd;
        rho_max = std::max({rho_max, kd.x, kd.y, kd.z});
        s_max = std::max(s_max, c.rs.rows[i].sum());
    }
    EXPECT_LE(results[1].iterations, std::uint64_t(std::ceil(std::log(o.tolerance) / std::log(rho_max * s_max))));
    // Stein–Rosenberg: for a non-negative iteration matrix with ρ(J) < 1, ρ(GS) < ρ(J).
    EXPECT_LT(results[2].iterations, results[1].iterations);
    EXPECT_EQ(results[3].iterations, 1u);
}

TEST(Methods, FurnaceByGatheringAndDirect) {
    // Every face E = 1, ρ = 0.99: B = 1/(1 − ρs) for the rows at hand (s their common sum), 100.
    const Scene scene =
        make_scene(std::vector<double>(6, 1.0), {grey("box", 0.99, 1.0)}, std::vector<std::uint32_t>(6, 0));
    for (SolverMethod m : {SolverMethod::Jacobi, SolverMethod::GaussSeidel, SolverMethod::Direct}) {
        ExactRowProvider provider(cube_rows());
        SolverOptions o;
        o.method = m;
        o.tolerance = 1e-12;
        const SolveResult r = solve_radiosity(scene, provider, o);
        ASSERT_EQ(r.stop, StopReason::Converged) << to_string(m);
        const double s = provider.rows()[0].sum();
        const double expected = 1.0 / (1.0 - 0.99 * s);
        // Gathering: |B − B*| ≤ 1/(1 − ρs) × τ × (emitted = 6) / (A = 1) ≈ 6e-10, plus the rounding
        // of one sweep (B_i recomputed from 6 terms: 6ε × B* ≈ 7e-14). Direct: N·cond·ε × B* with
        // cond_∞(I − ρF) ≤ (1 + ρ)/(1 − ρ) ≈ 200: 6 × 200 × 1.1e-16 × 100 ≈ 1.3e-11.
        for (const Vec3& b : r.radiosity) EXPECT_NEAR(b.y, expected, 6e-10 + 1.3e-11) << to_string(m);
        // Reciprocal (symmetric) and closed: the after-the-fact balance defect is rounding only, sums
        // of 6 × 6 terms of relative error ε against the turnover: 36 × 1.1e-16 = 4e-15 ≤ 1e-12.
        EXPECT_LE(r.energy.relative_error, 1e-12) << to_string(m);
        // escaped = Σ A B (1 − s) with |1 − s| a few ε: ≤ 6 × B* × 4ε ≈ 3e-13 ≤ 1e-12 × 6 × B*.
        EXPECT_LE(std::abs(r.energy.escaped.x), 1e-12 * r.energy.emitted.x * expected) << to_string(m);
        RecordProperty("iterations_" + to_string(m), std::to_string(r.iterations));
    }
}

TEST(Methods, NoEmittersEverywhere) {
    const Scene scene =
        make_scene(std::vector<double>(6, 1.0), {grey("box", 0.5, 0.0)}, std::vector<std::uint32_t>(6, 0));
    for (SolverMethod m : kAll) {
        ExactRowProvider provider(cube_rows());
        SolverOptions o;
        o.method = m;
        const SolveResult r = solve_radiosity(scene, provider, o);
        EXPECT_EQ(r.stop, StopReason::NothingToDo) << to_string(m);
        EXPECT_EQ(r.warnings.size(), 1u);
        for (const Vec3& b : r.radiosity) EXPECT_EQ(b, Vec3(0.0));
        EXPECT_EQ(provider.total_requests(), 0u);
    }
}

TEST(Methods, ReflectanceOfOneIsRefusedByEveryMethod) {
    const Scene scene = make_scene(std::vector<double>(6, 1.0),
                                   {grey("lamp", 0.5, 1.0), Material{"mirror", Vec3(0.5, 1.0, 0.5), Vec3(0.0)}},
                                   {0, 1, 0, 0, 0, 0});
    for (SolverMethod m : kAll) {
        ExactRowProvider provider(cube_rows());
        SolverOptions o;
        o.method = m;
        try {
            solve_radiosity(scene, provider, o);
            FAIL() << to_string(m) << ": expected InputError";
        } catch (const InputError& e) {
            const std::string what = e.what();
            EXPECT_NE(what.find("no steady state"), std::string::npos) << what;
            EXPECT_NE(what.find("mirror"), std::string::npos) << what;
            EXPECT_NE(what.find("green"), std::string::npos) << what;
        }
        EXPECT_EQ(provider.total_requests(), 0u);  // refused before any row is computed
    }
}

TEST(Methods, StiffRowsAreRefusedBeforeGathering) {
    std::vector<SparseRow> rows = cube_rows();
    for (double& v : rows[4].val) v *= 1.01;  // row 4 sums to 1.01; 0.995 × 1.01 > 1
    const Scene scene =
        make_scene(std::vector<double>(6, 1.0), {grey("box", 0.995, 1.0)}, std::vector<std::uint32_t>(6, 0));
    for (SolverMethod m : {SolverMethod::Jacobi, SolverMethod::GaussSeidel, SolverMethod::Direct}) {
        ExactRowProvider provider(rows);
        SolverOptions o;
        o.method = m;
        o.progress = [](const SolveProgress&) { FAIL() << "no sweep may run"; };
        try {
            solve_radiosity(scene, provider, o);
            FAIL() << "expected InputError";
        } catch (const InputError& e) {
            EXPECT_NE(std::string(e.what()).find("patch 4"), std::string::npos) << e.what();
        }
    }
}

TEST(Methods, InvalidRowValuesAreRefused) {
    std::vector<SparseRow> rows = cube_rows();
    rows[2].val[1] = NAN;
    const Scene scene =
        make_scene(std::vector<double>(6, 1.0), {grey("box", 0.5, 1.0)}, std::vector<std::uint32_t>(6, 0));
    ExactRowProvider provider(rows);
    SolverOptions o;
    o.method = SolverMethod::GaussSeidel;
    EXPECT_THROW(solve_radiosity(scene, provider, o), InputError);
}

TEST(Methods, DirectRefusedAboveItsLimitBeforeAnyRow) {
    const std::uint32_t n = kDirectMaxPatches + 1;
    std::vector<std::uint32_t> mat(n, 0);
    const Scene scene = make_scene(std::vector<double>(n, 1.0), {grey("lamp", 0.5, 1.0)}, mat);
    ExactRowProvider provider{std::vector<SparseRow>(n)};
    SolverOptions o;
    o.method = SolverMethod::Direct;
    try {
        solve_radiosity(scene, provider, o);
        FAIL() << "expected InputError";
    } catch (const InputError& e) {
        EXPECT_NE(std::string(e.what()).find("refused"), std::string::npos) << e.what();
    }
    EXPECT_EQ(provider.total_requests(), 0u);
}

TEST(Methods, ProviderOfAnotherSceneIsRefused) {
    const Scene scene =
        make_scene(std::vector<double>(6, 1.0), {grey("box", 0.5, 1.0)}, std::vector<std::uint32_t>(6, 0));
    ExactRowProvider provider(ring_rows(5));
    EXPECT_THROW(solve_radiosity(scene, provider, SolverOptions{}), InputError);
}

TEST(Methods, SweepProgressOncePerSweep) {
    const Case c = mixed_case();
    for (SolverMethod m : {SolverMethod::Jacobi, SolverMethod::GaussSeidel}) {
        ExactRowProvider provider(c.rs.rows);
        SolverOptions o;
        o.method = m;
        std::uint64_t calls = 0;
        o.progress = [&](const SolveProgress& p) { EXPECT_EQ(p.iterations, ++calls); };
        const SolveResult r = solve_radiosity(c.scene, provider, o);
        EXPECT_EQ(calls, r.iterations);
        EXPECT_EQ(provider.total_requests(), c.scene.size());  // every row, once
        EXPECT_EQ(r.history.back().unshot_fraction, r.unshot_fraction);
    }
}

TEST(Options, Validation) {
    SolverOptions o;
    EXPECT_NO_THROW(validate(o));
    o.overshoot = 2.0;
    EXPECT_THROW(validate(o), InputError);
    o.overshoot = 0.9;
    EXPECT_THROW(validate(o), InputError);
    o = SolverOptions{};
    o.tolerance = -1e-3;
    EXPECT_THROW(validate(o), InputError);
    o.tolerance = NAN;
    EXPECT_THROW(validate(o), InputError);
    o = SolverOptions{};
    o.batch = 0;
    EXPECT_THROW(validate(o), InputError);
    o = SolverOptions{};
    o.row_cache_mb = -1;
    EXPECT_THROW(validate(o), InputError);
    o = SolverOptions{};
    o.history_capacity = 1;
    EXPECT_THROW(validate(o), InputError);
}

TEST(Options, MethodNames) {
    for (SolverMethod m : kAll) EXPECT_EQ(parse_solver_method(to_string(m)), m);
    EXPECT_EQ(parse_solver_method("gauss-seidel"), SolverMethod::GaussSeidel);
    EXPECT_THROW(parse_solver_method("sor"), InputError);
    SolverOptions o;
    EXPECT_EQ(effective_max_iterations(o, 10), 100000u);
    EXPECT_EQ(effective_max_iterations(o, 1000), 1000000u);
    o.max_iterations = 7;
    EXPECT_EQ(effective_max_iterations(o, 1000), 7u);
}

TEST(Outputs, ObjectMeansAreAreaWeighted) {
    const Scene scene = make_scene({1.0, 3.0, 2.0}, {grey("m", 0.5, 0.0)}, {0, 0, 0}, {"floor", "lamp", "empty"},
                                   {0, 0, 1});
    const std::vector<Vec3> b{Vec3(2.0), Vec3(6.0, 4.0, 0.0), Vec3(7.0)};
    const std::vector<ObjectRadiosity> o = object_radiosity(scene, b);
    ASSERT_EQ(o.size(), 3u);
    EXPECT_EQ(o[0].name, "floor");
    EXPECT_EQ(o[0].area, 4.0);
    EXPECT_EQ(o[0].radiosity, Vec3(5.0, 3.5, 0.5));  // (1·2 + 3·6)/4, (2 + 12)/4, 2/4: exact
    EXPECT_EQ(o[1].radiosity, Vec3(7.0));
    EXPECT_EQ(o[2].area, 0.0);
    EXPECT_EQ(o[2].radiosity, Vec3(0.0));
}

TEST(Outputs, DisplayAddsReflectedAmbient) {
    const Scene scene = make_scene({1.0, 1.0}, {Material{"m", Vec3(0.5, 0.25, 0.0), Vec3(0.0)}}, {0, 0});
    const std::vector<Vec3> b{Vec3(1.0), Vec3(2.0)};
    const std::vector<Vec3> d = display_radiosity(scene, b, Vec3(4.0));
    EXPECT_EQ(d[0], Vec3(3.0, 2.0, 1.0));
    EXPECT_EQ(d[1], Vec3(4.0, 3.0, 2.0));
}

}  // namespace
}  // namespace ffcube
