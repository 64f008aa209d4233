// The solver's ETA (pipeline/solve.hpp, solve_eta_seconds): the time left for the unshot fraction
// to reach the tolerance, from its measured exponential decay between two progress samples.
#include <gtest/gtest.h>

#include <cmath>

#include "ffcube/pipeline/solve.hpp"

namespace ffcube {
namespace {

// f(t) = exp(−k t): sampled at t0 and t1, the rate measured is k, and f reaches tol at
// t = ln(1/tol)/k, so the time left from t1 is ln(1/tol)/k − t1. The values are a few
// logarithms and divisions of numbers of size ≤ 30: rounding, 1e-12 with room.
TEST(SolveEta, ExponentialDecayGivesTheClosedForm) {
    for (const double k : {0.1, 1.0, 7.5}) {
        const double t0 = 0.5, t1 = 2.0, tol = 1e-9;  // not reached by t1 for any k here
        const auto eta = solve_eta_seconds(t0, std::exp(-k * t0), t1, std::exp(-k * t1), tol);
        ASSERT_TRUE(eta.has_value()) << k;
        EXPECT_NEAR(*eta, std::log(1.0 / tol) / k - t1, 1e-12) << k;
    }
    // One decade a second from 1e-2: 1e-4 two seconds later.
    EXPECT_NEAR(*solve_eta_seconds(1.0, 1e-1, 2.0, 1e-2, 1e-4), 2.0, 1e-12);
}

TEST(SolveEta, NoDecayNoEta) {
    EXPECT_FALSE(solve_eta_seconds(1.0, 1e-2, 2.0, 1e-2, 1e-4).has_value());  // flat
    EXPECT_FALSE(solve_eta_seconds(1.0, 1e-2, 2.0, 2e-2, 1e-4).has_value());  // growing
    EXPECT_FALSE(solve_eta_seconds(2.0, 1e-1, 2.0, 1e-2, 1e-4).has_value());  // no time between
    EXPECT_FALSE(solve_eta_seconds(1.0, NAN, 2.0, 1e-2, 1e-4).has_value());
    EXPECT_FALSE(solve_eta_seconds(1.0, 1e-1, 2.0, 0.0, 1e-4).has_value());
    EXPECT_EQ(solve_eta_seconds(1.0, 1e-1, 2.0, 1e-5, 1e-4), 0.0);  // already there
}

}  // namespace
}  // namespace ffcube
