// Stiff scenes (issue 16): the furnace near ρ = 1 solved by every method to 1e-3 or refused,
// the default solve switching from shooting to its GMRES finish and saying so, the error bound
// against the true error, and divergence caught when the spectral radius of ρF is 1 or more.
#include <gtest/gtest.h>

#include <cmath>
#include <string>

#include "ffcube/core/error.hpp"
#include "ffcube/solver/convergence.hpp"
#include "ffcube/solver/linear.hpp"
#include "ffcube/solver/solver.hpp"
#include "fixtures.hpp"

namespace ffcube {
namespace {

using namespace ffcube::test;

// A closed enclosure of 96 equal patches (the count of a unit box meshed 4 × 4 per face) whose
// rows sum to 1 exactly: patch i sees the 64 patches i ± 1 … i ± 32 (mod 96), each with
// F = 2⁻⁶. Every value and every partial sum is exact in double, the rows are symmetric with
// equal areas (reciprocal), so B* = E/(1 − ρ) exactly for these rows.
constexpr std::uint32_t kPatches = 96;
std::vector<SparseRow> exact_furnace_rows() {
    std::vector<SparseRow> rows(kPatches);
    for (std::uint32_t i = 0; i < kPatches; ++i) {
        for (std::uint32_t j = 0; j < kPatches; ++j) {
            const std::uint32_t d = (j + kPatches - i) % kPatches;
            if (d != 0 && (d <= 32 || d >= kPatches - 32)) {
                rows[i].col.push_back(j);
                rows[i].val.push_back(1.0 / 64.0);
            }
        }
    }
    return rows;
}

Scene furnace96(double rho) {
    return make_scene(std::vector<double>(kPatches, 1.0), {grey("box", rho, 1.0)},
                      std::vector<std::uint32_t>(kPatches, 0));
}

// The tolerance for 1e-3. Shooting: B* − B = (I − K)⁻¹ K ΔB with ‖K‖_∞ = ρ (equal areas, symmetric
// rows summing to 1), so |B − B*|_∞ ≤ ρ/(1 − ρ) ‖ΔB‖_∞, and ‖ΔB‖_∞ ≤ τ × (emitted over RGB = 3N) /
// (A = 1): relative to B* = 1/(1 − ρ) at most 3Nτρ. Gathering: (I − ρF)(B* − B) = r, ‖ρF‖_∞ = ρ, so
// |B − B*|_∞ ≤ ‖r‖_∞/(1 − ρ) ≤ 3Nτ/(1 − ρ): relative 3Nτ. τ = 1e-6 gives 2.9e-4 ≤ 1e-3, leaving room
// for rounding (direct: N × cond × ε with cond_∞(I − ρF) ≤ (1 + ρ)/(1 − ρ) = 2e4: 2e-10).
constexpr double kTolerance = 1e-6;
constexpr double kRelative = 1e-3;

struct Case {
    double rho;
    SolverMethod method;
};
class StiffFurnace : public ::testing::TestWithParam<Case> {};

TEST_P(StiffFurnace, EveryMethodWithinOneInAThousandOrRefused) {
    const auto [rho, method] = GetParam();
    const Scene scene = furnace96(rho);
    ExactRowProvider provider(exact_furnace_rows());
    SolverOptions o;
    o.method = method;
    o.tolerance = kTolerance;
    const SolveResult r = solve_radiosity(scene, provider, o);
    RecordProperty("iterations", std::to_string(r.iterations));
    RecordProperty("action", r.stiffness.action);
    if (!r.converged()) {
        // The refusal: the CLI maps this to exit code 5.
        EXPECT_THROW(require_converged(r, o, false), NotConvergedError);
        EXPECT_NE(method, SolverMethod::Shoot) << "the default must converge on the furnace";
        EXPECT_NE(method, SolverMethod::Direct);
        return;
    }
    EXPECT_NO_THROW(require_converged(r, o, false));
    const double exact = 1.0 / (1.0 - rho);
    for (const Vec3& b : r.radiosity)
        for (int c = 0; c < 3; ++c) {
            ASSERT_TRUE(std::isfinite(b[c]));
            EXPECT_NEAR(b[c] / exact, 1.0, kRelative) << to_string(method) << " ρ " << rho;
        }
    // The reported bound holds: the mean error is at most the bound (shooting exactly; the rows are
    // reciprocal, so for gathering too).
    double mean_err = 0.0;
    for (const Vec3& b : r.radiosity) mean_err += std::abs(b.y - exact) / kPatches;
    EXPECT_LE(mean_err, r.error_bound.y * (1 + 1e-9) + 1e-12 * exact);
    EXPECT_LE(r.error_bound_relative, 3 * kTolerance * 1.01);  // U_c ≤ τ × 3N, bound U_c/((1 − ρ)N) over 1/(1 − ρ)
    EXPECT_FALSE(r.ambient_included);
    if (method == SolverMethod::Shoot && rho >= 0.99) {
        // Plain shooting would need about N ln(1/τ) / (1 − ρ) shots: the default switched.
        EXPECT_TRUE(r.stiffness.stiff);
        EXPECT_EQ(r.stiffness.action, "gmres");
        EXPECT_FALSE(r.stiffness.reason.empty());
        EXPECT_GT(r.stiffness.krylov_products, 0u);
        EXPECT_LT(r.shots, 10u * kPatches);
        EXPECT_EQ(r.cache.rows_computed, kPatches);  // the finish used the cached rows
        EXPECT_NEAR(r.stiffness.rho_max, rho, 0.0);
        EXPECT_EQ(r.stiffness.max_row_sum, 1.0);
    }
}

std::string case_name(const ::testing::TestParamInfo<Case>& info) {
    std::string m = to_string(info.param.method);
    for (char& ch : m)
        if (ch == '-') ch = '_';
    return m + "_" + std::to_string(int(std::round(-std::log10(1 - info.param.rho)))) + "_nines";
}

INSTANTIATE_TEST_SUITE_P(
    Rho, StiffFurnace,
    ::testing::Values(Case{0.9, SolverMethod::Shoot}, Case{0.99, SolverMethod::Shoot}, Case{0.999, SolverMethod::Shoot},
                      Case{0.9999, SolverMethod::Shoot}, Case{0.9, SolverMethod::Jacobi},
                      Case{0.99, SolverMethod::Jacobi}, Case{0.999, SolverMethod::Jacobi},
                      Case{0.9999, SolverMethod::Jacobi}, Case{0.9, SolverMethod::GaussSeidel},
                      Case{0.99, SolverMethod::GaussSeidel}, Case{0.999, SolverMethod::GaussSeidel},
                      Case{0.9999, SolverMethod::GaussSeidel}, Case{0.9, SolverMethod::Direct},
                      Case{0.99, SolverMethod::Direct}, Case{0.999, SolverMethod::Direct},
                      Case{0.9999, SolverMethod::Direct}),
    case_name);

TEST(Stiff, DefaultToleranceOnTheFurnaceIsWithinItsBound) {
    // The default τ = 1e-4 at ρ = 0.999: converged, and the mean is within the reported bound.
    const Scene scene = furnace96(0.999);
    ExactRowProvider provider(exact_furnace_rows());
    const SolveResult r = solve_radiosity(scene, provider, SolverOptions{});
    ASSERT_EQ(r.stop, StopReason::Converged);
    EXPECT_EQ(r.stiffness.action, "gmres");
    double mean = 0.0;
    for (const Vec3& b : r.radiosity) mean += b.x / kPatches;
    EXPECT_LE(std::abs(mean - 1000.0), r.error_bound.x);
    EXPECT_LE(r.error_bound_relative, 1e-3);
}

TEST(Stiff, UnconvergedShootingReportsABoundThatHolds) {
    // Plain shooting stopped early at ρ = 0.999: far from B*, and the bound says so truthfully.
    const Scene scene = furnace96(0.999);
    ExactRowProvider provider(exact_furnace_rows());
    SolverOptions o;
    o.stiff_switch = false;
    o.max_iterations = 5000;
    const SolveResult r = solve_radiosity(scene, provider, o);
    ASSERT_EQ(r.stop, StopReason::IterationLimit);
    EXPECT_FALSE(r.converged());
    EXPECT_THROW(require_converged(r, o, false), NotConvergedError);
    EXPECT_NO_THROW(require_converged(r, o, true));
    double mean_err = 0.0;
    for (const Vec3& b : r.radiosity) mean_err += std::abs(b.z - 1000.0) / kPatches;
    EXPECT_GT(mean_err, 100.0);
    EXPECT_LE(mean_err, r.error_bound.z);
    // Here the bound is nearly tight: the unshot power, reflected on, is exactly what is missing.
    EXPECT_LE(r.error_bound.z, 1.01 * mean_err / 0.999);
    const std::string what = describe_unconverged(r, o);
    EXPECT_NE(what.find("iteration limit"), std::string::npos) << what;
}

TEST(Stiff, ModerateScenesKeepPlainShooting) {
    // ρ = 0.5: shooting converges in a few generations; nothing is switched.
    const Scene scene = furnace96(0.5);
    ExactRowProvider provider(exact_furnace_rows());
    const SolveResult r = solve_radiosity(scene, provider, SolverOptions{});
    ASSERT_EQ(r.stop, StopReason::Converged);
    EXPECT_EQ(r.stiffness.action, "none");
    EXPECT_FALSE(r.stiffness.stiff);
    EXPECT_GT(r.stiffness.predicted_generations, 0.0);
}

// Jacobi and Gauss–Seidel on (I − ρF) B = 1 for the unit cube's rows (sum 1): at ρ = 1 the
// spectral radius of ρF is 1 (no steady state: B grows without bound, the residual stays), at
// ρ = 1.05 it is 1.05 (the residual grows). The solver refuses such input (ρ ≥ 1, ρ × rowsum ≥ 1),
// so the systems are built here at the API level. Either way: stopped as diverged, no NaN, no
// endless loop.
DenseSystem cube_system(double rho) {
    const std::vector<SparseRow> rows = cube_rows();
    DenseSystem s{DenseMatrix(6), std::vector<double>(6, 1.0)};
    for (std::uint32_t i = 0; i < 6; ++i) {
        s.a(i, i) = 1.0;
        for (std::size_t k = 0; k < rows[i].nnz(); ++k) s.a(i, rows[i].col[k]) -= rho * rows[i].val[k];
    }
    return s;
}

TEST(Stiff, SweepsStopWhenTheSpectralRadiusIsOneOrMore) {
    for (double rho : {1.0, 1.05})
        for (Sweep sweep : {Sweep::Jacobi, Sweep::GaussSeidel}) {
            const DenseSystem s = cube_system(rho);
            std::vector<double> x(6, 1.0);
            const std::span<double> xs[1] = {x};
            const std::vector<double> w(6, 1.0);
            SweepControl control;
            control.sweep = sweep;
            control.tolerance = 1e-4;
            control.max_sweeps = 10'000'000;
            const SweepOutcome out = sweep_until<DenseSystem>(std::span(&s, 1), xs, w, 6.0, control, {});
            EXPECT_EQ(out.stop, StopReason::Diverged) << "ρ " << rho;
            EXPECT_LE(out.sweeps, 1000u) << "ρ " << rho;
            if (rho == 1.0) {
                EXPECT_TRUE(out.stagnated);  // constant residual: only the stagnation rule sees it
            }
            for (double v : x) EXPECT_TRUE(std::isfinite(v));
        }
}

TEST(Stiff, GmresStopsOnASingularSystem) {
    // ρ = 1: I − F is singular and b = 1 is outside its range (the rows sum to 1): no solution.
    const DenseSystem s = cube_system(1.0);
    const LinearOperator a = [&](std::span<const double> x, std::span<double> y) {
        for (std::uint32_t i = 0; i < 6; ++i) {
            y[i] = 0.0;
            for (std::uint32_t j = 0; j < 6; ++j) y[i] += s.a(i, j) * x[j];
        }
    };
    std::vector<double> x(6, 0.0);
    GmresControl c;
    c.tolerance = 1e-9;
    c.inner_tolerance = 1e-10;
    const auto l1 = [](std::span<const double> r) {
        double t = 0.0;
        for (double v : r) t += std::abs(v);
        return t;
    };
    const GmresOutcome out = gmres(a, s.b, x, c, l1);
    EXPECT_FALSE(out.converged);
    EXPECT_TRUE(out.stagnated);
    EXPECT_LT(out.iterations, 200u);
    for (double v : x) EXPECT_TRUE(std::isfinite(v));
}

TEST(Stiff, GmresSolvesTheTextbookSystem) {
    // [[2, 1], [1, 2]] x = [8, 10]: x = (2, 4), in two Krylov steps.
    const LinearOperator a = [](std::span<const double> x, std::span<double> y) {
        y[0] = 2 * x[0] + x[1];
        y[1] = x[0] + 2 * x[1];
    };
    const std::vector<double> b{8.0, 10.0};
    std::vector<double> x{0.0, 0.0};
    GmresControl c;
    c.tolerance = 1e-12;
    c.inner_tolerance = 1e-13;
    const GmresOutcome out = gmres(a, b, x, c, [](std::span<const double> r) { return std::abs(r[0]) + std::abs(r[1]); });
    ASSERT_TRUE(out.converged);
    EXPECT_NEAR(x[0], 2.0, 1e-12);
    EXPECT_NEAR(x[1], 4.0, 1e-12);
    EXPECT_LE(out.iterations, 4u);  // two products in the cycle, one or two true residuals
}

}  // namespace
}  // namespace ffcube
