// The iterative and direct core on plain linear systems, and the stopping machinery.
#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <vector>

#include "ffcube/core/error.hpp"
#include "ffcube/solver/convergence.hpp"
#include "ffcube/solver/linear.hpp"

namespace ffcube {
namespace {

// [[2,1],[1,2]] x = [8,10], solution (2,4).
DenseSystem classic() {
    DenseSystem s{DenseMatrix(2), {8.0, 10.0}};
    s.a(0, 0) = 2;
    s.a(0, 1) = 1;
    s.a(1, 0) = 1;
    s.a(1, 1) = 2;
    return s;
}

using Table = std::vector<std::array<double, 2>>;

// Every value in these tables is a dyadic fraction with few bits, and each sweep computes
// (b_i − a_ij x_j) / 2 with such numbers, which double represents exactly: the comparison is exact.
void expect_table(Sweep sweep, std::array<double, 2> x0, const Table& expected) {
    const DenseSystem s = classic();
    std::vector<double> x(x0.begin(), x0.end()), next(2);
    for (const auto& row : expected) {
        if (sweep == Sweep::Jacobi) {
            jacobi_sweep(s, x, next);
            x = next;
        } else {
            gauss_seidel_sweep(s, std::span<double>(x));
        }
        EXPECT_EQ(x[0], row[0]);
        EXPECT_EQ(x[1], row[1]);
    }
}

TEST(LinearCore, JacobiTableFromZero) {
    expect_table(Sweep::Jacobi, {0, 0}, {{4, 5}, {1.5, 3}, {2.5, 4.25}, {1.875, 3.75}});
}

TEST(LinearCore, GaussSeidelTableFromZero) {
    expect_table(Sweep::GaussSeidel, {0, 0}, {{4, 3}, {2.5, 3.75}, {2.125, 3.9375}, {2.03125, 3.984375}});
}

TEST(LinearCore, JacobiTableFromBetterStart) {
    // x1 = ((8−3)/2, (10−2)/2), then the same rule: hand-computed.
    expect_table(Sweep::Jacobi, {2, 3}, {{2.5, 4}, {2, 3.75}, {2.125, 4}, {2, 3.9375}});
}

TEST(LinearCore, GaussSeidelTableFromBetterStart) {
    expect_table(Sweep::GaussSeidel, {2, 3}, {{2.5, 3.75}, {2.125, 3.9375}, {2.03125, 3.984375}, {2.0078125, 3.99609375}});
}

TEST(LinearCore, LuSolvesClassicExactly) {
    // Pivot 2, multiplier 1/2, u22 = 3/2, y = (8, 6), x = (2, 4): every step exact in binary.
    DenseSystem s = classic();
    std::vector<std::uint32_t> perm;
    std::vector<double> x = s.b, scratch(2);
    lu_factor(s.a, perm, "classic");
    lu_solve(s.a, perm, x, scratch);
    EXPECT_EQ(x[0], 2.0);
    EXPECT_EQ(x[1], 4.0);
}

TEST(LinearCore, LuPivotsPastZeroDiagonal) {
    // a_00 = 0: without row exchanges the factorisation would divide by zero.
    const double a[3][3] = {{0, 1, 2}, {1, 0, 3}, {4, 5, 6}};
    const double x_true[3] = {1, -2, 3};
    DenseMatrix m(3);
    std::vector<double> b(3, 0.0), scratch(3);
    for (std::uint32_t i = 0; i < 3; ++i)
        for (std::uint32_t j = 0; j < 3; ++j) {
            m(i, j) = a[i][j];
            b[i] += a[i][j] * x_true[j];  // small integers: b is exact
        }
    std::vector<std::uint32_t> perm;
    lu_factor(m, perm, "pivot test");
    lu_solve(m, perm, b, scratch);
    // LU with partial pivoting is backward stable: |x − x*| / |x*| ≲ n · cond(A) · ε. Here
    // cond_∞(A) = ‖A‖‖A⁻¹‖ = 15 × 1.375 ≈ 21 (A⁻¹ from the adjugate, det = 16), so the bound is
    // 3 × 21 × 1.1e-16 × |x*|_∞ (= 3) ≈ 2e-14.
    for (int i = 0; i < 3; ++i) EXPECT_NEAR(b[i], x_true[i], 2e-14);
}

TEST(LinearCore, LuRefusesSingular) {
    DenseMatrix m(2);
    m(0, 0) = 1;
    m(0, 1) = 2;
    m(1, 0) = 2;
    m(1, 1) = 4;
    std::vector<std::uint32_t> perm;
    EXPECT_THROW(lu_factor(m, perm, "singular test"), InputError);
}

TEST(SweepDriver, ConvergesOnClassicToTolerance) {
    const std::array<DenseSystem, 1> systems{classic()};
    std::vector<double> x{0, 0};
    const std::array<std::span<double>, 1> xs{x};
    const std::vector<double> weights{1, 1};
    SweepControl control;
    control.sweep = Sweep::GaussSeidel;
    control.tolerance = 1e-12;
    std::uint64_t calls = 0;
    const SweepOutcome out =
        sweep_until<DenseSystem>(systems, xs, weights, 18.0, control, [&](std::uint64_t, double) { ++calls; });
    EXPECT_EQ(out.stop, StopReason::Converged);
    // After a Gauss–Seidel sweep the last row holds exactly, and r_0 = 8 − 2x_0 − x_1: −3 after
    // sweep 1 (x = (4,3)), then a quarter of that per sweep (ρ(G) = 1/4), so the fraction is
    // (3/18)·4^−(k−1), exact in binary. It is ≤ 1e-12 first when 4^(k−1) ≥ 1.67e11: k − 1 ≥ 18.6, k = 20.
    EXPECT_EQ(out.sweeps, 20u);
    EXPECT_EQ(calls, out.sweeps + 1);  // once per sweep and once for the start
    // Residual ≤ 1e-12 × 18 and ‖A⁻¹‖_∞ = 1: the error is below 2e-11.
    EXPECT_NEAR(x[0], 2.0, 2e-11);
    EXPECT_NEAR(x[1], 4.0, 2e-11);
}

TEST(SweepDriver, JacobiOnNonDominantSystemDiverges) {
    // [[1,2],[2,1]] x = [3,3]: Jacobi's iteration matrix [[0,−2],[−2,0]] has eigenvalues ±2.
    // From x = 0 the residual is (3,3)·(−2)^k: fraction 1, 2, 4, ... (reference Σ|b| = 6).
    // The monitor flags it once the fraction exceeds 1000 × its best (1) with no improvement for 3
    // sweeps: 2^10 = 1024 > 1000 at sweep 10, and 2^9 = 512 is not.
    std::array<DenseSystem, 1> systems{DenseSystem{DenseMatrix(2), {3.0, 3.0}}};
    systems[0].a(0, 0) = 1;
    systems[0].a(0, 1) = 2;
    systems[0].a(1, 0) = 2;
    systems[0].a(1, 1) = 1;
    std::vector<double> x{0, 0};
    const std::array<std::span<double>, 1> xs{x};
    const std::vector<double> weights{1, 1};
    SweepControl control;
    control.sweep = Sweep::Jacobi;
    control.max_sweeps = 1000;
    const SweepOutcome out = sweep_until<DenseSystem>(systems, xs, weights, 6.0, control, {});
    EXPECT_EQ(out.stop, StopReason::Diverged);
    EXPECT_EQ(out.sweeps, 10u);
    EXPECT_EQ(out.residual_fraction, 1024.0);
}

TEST(SweepDriver, IterationLimit) {
    const std::array<DenseSystem, 1> systems{classic()};
    std::vector<double> x{0, 0};
    const std::array<std::span<double>, 1> xs{x};
    const std::vector<double> weights{1, 1};
    SweepControl control;
    control.sweep = Sweep::Jacobi;
    control.tolerance = 0.0;
    control.max_sweeps = 4;
    const SweepOutcome out = sweep_until<DenseSystem>(systems, xs, weights, 18.0, control, {});
    EXPECT_EQ(out.stop, StopReason::IterationLimit);
    EXPECT_EQ(out.sweeps, 4u);
    EXPECT_EQ(x[0], 1.875);  // the fourth row of the Jacobi table
    EXPECT_EQ(x[1], 3.75);
}

TEST(DivergenceMonitor, GeometricGrowthIsCaught) {
    DivergenceMonitor m(5, 1000.0);
    double v = 1.0;
    int steps = 0;
    while (!m.update(v)) {
        v *= 1.5;
        ++steps;
        ASSERT_LT(steps, 100);
    }
    // 1.5^k > 1000 first at k = 18 (1.5^17 ≈ 985); the window of 5 is long passed by then.
    EXPECT_EQ(steps, 18);
}

TEST(DivergenceMonitor, TransientRiseIsNot) {
    // Rises to 500× the best and comes back: below the growth factor, so never flagged.
    DivergenceMonitor m(5, 1000.0);
    for (double v : {1.0, 10.0, 100.0, 500.0, 400.0, 300.0, 100.0, 10.0, 1.0, 0.5, 0.1}) EXPECT_FALSE(m.update(v));
}

TEST(DivergenceMonitor, JumpNeedsTheWindow) {
    // A sudden 10⁴× jump is flagged only after `window` updates without improvement.
    DivergenceMonitor m(3, 1000.0);
    EXPECT_FALSE(m.update(1.0));
    EXPECT_FALSE(m.update(1e4));
    EXPECT_FALSE(m.update(1e4));
    EXPECT_TRUE(m.update(1e4));
}

TEST(DivergenceMonitor, NonFiniteIsDivergence) {
    DivergenceMonitor m(100, 1000.0);
    EXPECT_FALSE(m.update(1.0));
    EXPECT_TRUE(m.update(NAN));
    DivergenceMonitor m2(100, 1000.0);
    EXPECT_TRUE(m2.update(INFINITY));
}

TEST(ConvergenceHistory, BoundedUniformAndEndsWithLast) {
    ConvergenceHistory h(8);
    for (int k = 0; k < 1000; ++k) h.offer(k, 1.0 / (k + 1));
    h.finish(999, 1.0 / 1000);
    const auto& s = h.samples();
    ASSERT_LE(s.size(), 8u);
    EXPECT_EQ(s.front().seconds, 0.0);
    EXPECT_EQ(s.back().seconds, 999.0);
    EXPECT_EQ(s.back().unshot_fraction, 1.0 / 1000);
    // Kept samples (all but the final one) are equally spaced in offer count.
    ASSERT_GE(s.size(), 3u);
    const double stride = s[1].seconds - s[0].seconds;
    for (std::size_t k = 1; k + 1 < s.size(); ++k) EXPECT_EQ(s[k].seconds - s[k - 1].seconds, stride);
}

TEST(ConvergenceHistory, ShortRunKeepsEverything) {
    ConvergenceHistory h(16);
    for (int k = 0; k < 5; ++k) h.offer(k, 1.0);
    h.finish(4, 1.0);  // equal to the last sample: not repeated
    EXPECT_EQ(h.samples().size(), 5u);
}

TEST(StopReason, Names) {
    EXPECT_EQ(to_string(StopReason::Converged), "converged");
    EXPECT_EQ(to_string(StopReason::IterationLimit), "iteration_limit");
    EXPECT_EQ(to_string(StopReason::Diverged), "diverged");
    EXPECT_EQ(to_string(StopReason::NothingToDo), "nothing_to_do");
}

}  // namespace
}  // namespace ffcube
