// Hottel's total exchange factors (View3D's emit=1) against closed forms.
#include <gtest/gtest.h>

#include "ffcube/solver/exchange.hpp"

namespace ffcube {
namespace {

TEST(Exchange, InfiniteParallelPlatesGiveTheClassicalFormula) {
    // Two infinite parallel plates: F_12 = F_21 = 1, equal areas. Net exchange between grey plates
    // (e.g. Modest, Radiative Heat Transfer, eq. 5.42): script-F_12 = 1 / (1/ε1 + 1/ε2 − 1).
    const double e1 = 0.8, e2 = 0.3;
    const auto X = hottel_exchange_factors({{0.0, 1.0}, {1.0, 0.0}}, {1.0, 1.0}, {e1, e2});
    const double exact = 1.0 / (1.0 / e1 + 1.0 / e2 - 1.0);
    EXPECT_NEAR(X[0][1], exact, 1e-14);  // a 2 × 2 LU: rounding only
    EXPECT_NEAR(X[1][0], exact, 1e-14);
    // What plate 1 emits and re-absorbs after reflections: ε1 − script-F_12 (a closed pair).
    EXPECT_NEAR(X[0][0], e1 - exact, 1e-14);
}

TEST(Exchange, ClosedEnclosureRowsSumToTheEmissivityAndBlackIsTheFormFactor) {
    // A reciprocal, closed 3-surface enclosure: areas 1, 2, 3 and A_i F_ij symmetric.
    const std::vector<double> area = {1.0, 2.0, 3.0};
    // Interchange areas AF (symmetric, row sums = areas): AF01 = 0.4, AF02 = 0.6, AF12 = 1.4,
    // AF11 = 0.2, AF22 = 1.0.
    const double AF[3][3] = {{0.0, 0.4, 0.6}, {0.4, 0.2, 1.4}, {0.6, 1.4, 1.0}};
    std::vector<std::vector<double>> G(3, std::vector<double>(3));
    for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j) G[i][j] = AF[i][j] / area[i];
    const std::vector<double> eps = {0.9, 0.5, 0.2};
    const auto X = hottel_exchange_factors(G, area, eps);
    for (int i = 0; i < 3; ++i) {
        double sum = 0.0;
        for (int j = 0; j < 3; ++j) sum += X[i][j];
        EXPECT_NEAR(sum, eps[i], 1e-13);  // energy: all that i emits is absorbed somewhere
        for (int j = 0; j < 3; ++j) EXPECT_NEAR(area[i] * X[i][j], area[j] * X[j][i], 1e-13);  // reciprocity
    }
    // Black surfaces: no reflection, script-F is F.
    const auto B = hottel_exchange_factors(G, area, {1.0, 1.0, 1.0});
    for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j) EXPECT_NEAR(B[i][j], G[i][j], 1e-15);
}

}  // namespace
}  // namespace ffcube
