// Gray-body exchange (solver/radiate.hpp) against closed forms, on form factors built by hand.
//
// Tolerances. Every F here holds only values that float represents exactly (0, 1/4, 3/4, 1/2, 1),
// so the CsrMatrix's float storage adds no error and the only error is the solve's: GMRES stops
// at a relative residual ‖b − AJ‖₂ ≤ τ‖b‖₂ (τ = 1e-13 here), and ‖J − J*‖/‖J*‖ ≤ cond(A) τ with
// cond(A) ≤ ‖A‖ ‖A⁻¹‖ ≤ 2 × (1/ε_min) (A = I − diag(c)F, ‖diag(c)F‖ ≤ 1, and for a closed enclosure
// the slowest mode decays as ε_min). At ε_min = 0.02 that is 1e-11 in J; a flux q = ε(σT⁴ − G) is
// a difference of J-sized terms, so relative to q it is that over q/(σT⁴), at least 1e-2 in these
// cases: 1e-9 — hence 1e-10 where ε ≥ 0.3 (error ≤ 7e-13 / 0.1) and 1e-8 at ε = 0.02.
#include <gtest/gtest.h>

#include <cmath>
#include <iostream>
#include <vector>

#include "ffcube/core/error.hpp"
#include "ffcube/solver/radiate.hpp"
#include "support/rows.hpp"

namespace ffcube {
namespace {

constexpr double kSigma = 5.670374419e-8;

using test::dense_to_csr;

SurfaceSpec temp(double eps, double t) { return {eps, SurfaceCondition::Temperature, t}; }
SurfaceSpec flux(double eps, double q) { return {eps, SurfaceCondition::HeatFlux, q}; }

RadiateOptions tight() {
    RadiateOptions o;
    o.tolerance = 1e-13;
    return o;
}

// Two-surface enclosure: body 1 (convex, A1) inside body 2 (A2). F11 = 0, F12 = 1, F21 = A1/A2,
// F22 = 1 − A1/A2. A1 = 1, A2 = 4: every entry exact in float.
constexpr double kA1 = 1.0, kA2 = 4.0;
CsrMatrix two_surface() { return dense_to_csr({{0.0, 1.0}, {kA1 / kA2, 1.0 - kA1 / kA2}}); }

// The closed form (Incropera & DeWitt eq. 13.25 with F12 = 1): net power from 1 to 2.
double two_surface_power(double e1, double e2, double t1, double t2) {
    return kSigma * (std::pow(t1, 4) - std::pow(t2, 4)) * kA1 / (1.0 / e1 + (kA1 / kA2) * (1.0 / e2 - 1.0));
}

struct Case {
    double e1, e2, tol;
};

TEST(Radiate, TwoSurfaceEnclosureMatchesClosedForm) {
    const CsrMatrix F = two_surface();
    const std::vector<double> area{kA1, kA2};
    // The tolerances: the header's derivation (1e-10 for ε ≥ 0.3, 1e-8 at ε = 0.02).
    for (const Case c : {Case{0.6, 0.3, 1e-10}, Case{1.0, 1.0, 1e-10}, Case{0.9, 1.0, 1e-10}, Case{0.02, 0.02, 1e-8}}) {
        SCOPED_TRACE(testing::Message() << "eps " << c.e1 << ", " << c.e2);
        const double t1 = 1000.0, t2 = 300.0;
        const RadiateResult r = solve_radiation(F, area, std::vector{temp(c.e1, t1), temp(c.e2, t2)}, tight());
        const double p = two_surface_power(c.e1, c.e2, t1, t2);
        EXPECT_NEAR(r.heat_flux[0] * kA1, p, c.tol * p);
        EXPECT_NEAR(r.heat_flux[1] * kA2, -p, c.tol * p);
        std::cout << "[measured] two-surface eps " << c.e1 << "," << c.e2 << ": rel error "
                  << std::abs(r.heat_flux[0] * kA1 - p) / p << ", " << std::abs(r.heat_flux[1] * kA2 + p) / p << "\n";
        EXPECT_NEAR(r.power, 0.0, c.tol * p);  // closed, reciprocal: everything 1 emits, 2 absorbs
        EXPECT_LE(r.balance_error, c.tol);
        EXPECT_NEAR(r.sky, 0.0, 1e-12 * p);
        // J = G + q on every patch.
        for (int i = 0; i < 2; ++i) EXPECT_NEAR(r.radiosity[i] - r.irradiation[i], r.heat_flux[i], c.tol * p);
    }
}

TEST(Radiate, GivenHeatFluxRecoversTheTemperature) {
    // Body 2 given the flux the closed form says it must take at T2 = 300 K: T2 comes back.
    const CsrMatrix F = two_surface();
    const std::vector<double> area{kA1, kA2};
    for (const Case c : {Case{0.6, 0.3, 1e-10}, Case{0.02, 0.02, 1e-8}}) {
        const double p = two_surface_power(c.e1, c.e2, 1000.0, 300.0);
        const RadiateResult r = solve_radiation(F, area, std::vector{temp(c.e1, 1000.0), flux(c.e2, -p / kA2)}, tight());
        EXPECT_NEAR(r.heat_flux[0] * kA1, p, c.tol * p);
        // T from σT⁴: dT/T = (1/4) d(σT⁴)/σT⁴, and σT⁴ = G + q/ε carries the relative error of G.
        EXPECT_NEAR(r.temperature[1], 300.0, 300.0 * c.tol);
        EXPECT_DOUBLE_EQ(r.temperature[0], 1000.0);
    }
}

// Three-surface enclosure with an adiabatic (reradiating) wall: an infinitely long triangular
// duct of sides L1 = 1, L2 = 1, LR = 1.5 (per unit depth). Crossed strings: F_ab = (La + Lb − Lc)/(2La):
// F12 = 0.25, F1R = 0.75, F21 = 0.25, F2R = 0.75, FR1 = FR2 = 0.5 (all exact in float).
TEST(Radiate, ReradiatingWallMatchesTextbookFormula) {
    const CsrMatrix F = dense_to_csr({{0.0, 0.25, 0.75}, {0.25, 0.0, 0.75}, {0.5, 0.5, 0.0}});
    const std::vector<double> area{1.0, 1.0, 1.5};
    for (const Case c : {Case{0.8, 0.4, 1e-10}, Case{0.02, 0.02, 1e-8}}) {
        SCOPED_TRACE(testing::Message() << "eps " << c.e1 << ", " << c.e2);
        const double t1 = 800.0, t2 = 400.0;
        const RadiateResult r =
            solve_radiation(F, area, std::vector{temp(c.e1, t1), temp(c.e2, t2), flux(0.5, 0.0)}, tight());
        // Incropera & DeWitt eq. 13.30: q1 = σ(T1⁴ − T2⁴) / [(1−ε1)/(ε1A1) + 1/(A1F12 + 1/(1/(A1F1R) +
        // 1/(A2F2R))) + (1−ε2)/(ε2A2)] (W).
        const double a1 = 1.0, a2 = 1.0;
        const double space = 1.0 / (a1 * 0.25 + 1.0 / (1.0 / (a1 * 0.75) + 1.0 / (a2 * 0.75)));
        const double p = kSigma * (std::pow(t1, 4) - std::pow(t2, 4)) /
                         ((1.0 - c.e1) / (c.e1 * a1) + space + (1.0 - c.e2) / (c.e2 * a2));
        EXPECT_NEAR(r.heat_flux[0] * a1, p, c.tol * p);
        EXPECT_NEAR(r.heat_flux[1] * a2, -p, c.tol * p);
        std::cout << "[measured] reradiating eps " << c.e1 << "," << c.e2 << ": rel error "
                  << std::abs(r.heat_flux[0] * a1 - p) / p << ", " << std::abs(r.heat_flux[1] * a2 + p) / p << "\n";
        EXPECT_EQ(r.heat_flux[2], 0.0);
        // The wall's radiosity sits between J1 and J2 by the two space resistances (eq. 13.31):
        // (J1 − JR) A1 F1R = (JR − J2) A2 F2R, and an adiabatic wall has σT_R⁴ = J_R = G_R.
        const double jr = (r.radiosity[0] * a1 * 0.75 + r.radiosity[1] * a2 * 0.75) / (a1 * 0.75 + a2 * 0.75);
        EXPECT_NEAR(r.radiosity[2], jr, c.tol * jr);
        EXPECT_NEAR(kSigma * std::pow(r.temperature[2], 4), jr, c.tol * jr);
        // Its emissivity does not matter (docs/radiate.md).
        const RadiateResult other =
            solve_radiation(F, area, std::vector{temp(c.e1, t1), temp(c.e2, t2), flux(0.05, 0.0)}, tight());
        EXPECT_NEAR(other.heat_flux[0], r.heat_flux[0], c.tol * p);
        EXPECT_NEAR(other.temperature[2], r.temperature[2], c.tol * r.temperature[2]);
    }
}

// A published three-surface example: the paint-baking oven of Incropera & DeWitt (Fundamentals of
// Heat and Mass Transfer, ch. 13, "radiation exchange with a reradiating surface"): a long duct whose
// cross-section is an equilateral triangle of side W = 1 m; the heated side at T1 = 1200 K, ε1 = 0.8;
// the painted panels at T2 = 500 K, ε2 = 0.4; the third side insulated (reradiating), ε = 0.8.
// Published: the heat supplied q1' = 37 kW/m, the insulated side at T_R = 1102 K. Per unit length,
// F_ij = 0.5 between any two sides (crossed strings), areas 1 m²/m. The book uses σ = 5.67e-8 and
// rounds q1' to 2 digits: our σ differs by 6.6e-5 relative, so the bounds are the rounding, ±0.5 kW/m
// and ±0.5 K (T_R is from σT⁴, in which σ cancels: J_R = (J1 + J2)/2 scales with σ).
TEST(Radiate, PaintBakingOvenMatchesPublishedNumbers) {
    const CsrMatrix F = dense_to_csr({{0.0, 0.5, 0.5}, {0.5, 0.0, 0.5}, {0.5, 0.5, 0.0}});
    const RadiateResult r = solve_radiation(F, std::vector{1.0, 1.0, 1.0},
                                            std::vector{temp(0.8, 1200.0), temp(0.4, 500.0), flux(0.8, 0.0)}, tight());
    EXPECT_NEAR(r.heat_flux[0], 37e3, 0.5e3);
    EXPECT_NEAR(r.heat_flux[1], -37e3, 0.5e3);
    EXPECT_NEAR(r.temperature[2], 1102.0, 0.5);
    std::cout << "[measured] paint-baking oven: q1 " << r.heat_flux[0] << " W/m (published 37 kW/m), T_R "
              << r.temperature[2] << " K (published 1102 K)\n";
}

TEST(Radiate, OpenPlateFacingTheSky) {
    // One patch that sees nothing: F = [0], F_sky = 1. q = εσ(T⁴ − T_sky⁴).
    const CsrMatrix F = dense_to_csr({{0.0}});
    const std::vector<double> area{2.0};
    RadiateOptions o = tight();
    EXPECT_THROW(solve_radiation(F, area, std::vector{temp(0.7, 350.0)}, o), InputError);
    try {
        solve_radiation(F, area, std::vector{temp(0.7, 350.0)}, o);
    } catch (const InputError& e) {
        EXPECT_NE(std::string(e.what()).find("100% of the hemisphere escapes"), std::string::npos) << e.what();
    }
    o.sky_temperature = 250.0;
    const RadiateResult r = solve_radiation(F, area, std::vector{temp(0.7, 350.0)}, o);
    const double q = 0.7 * kSigma * (std::pow(350.0, 4) - std::pow(250.0, 4));
    EXPECT_NEAR(r.heat_flux[0], q, 1e-12 * q);
    EXPECT_NEAR(r.sky, q * 2.0, 1e-12 * q);  // everything it loses goes to the sky
    EXPECT_LE(r.balance_error, 1e-12);
    // Heated plate: given q, T = (T_sky⁴ + q/(εσ))^(1/4).
    const RadiateResult h = solve_radiation(F, area, std::vector{flux(0.7, q)}, o);
    EXPECT_NEAR(h.temperature[0], 350.0, 350.0 * 1e-12);
}

TEST(Radiate, RefusesWhatHasNoAnswer) {
    const CsrMatrix F = two_surface();
    const std::vector<double> area{kA1, kA2};
    // Every surface a heat flux, no sky: T undetermined.
    EXPECT_THROW(solve_radiation(F, area, std::vector{flux(0.5, 0.0), flux(0.5, 0.0)}, tight()), InputError);
    // A sink that absorbs more than it receives: below 0 K.
    EXPECT_THROW(solve_radiation(F, area, std::vector{temp(0.5, 300.0), flux(0.5, -1e6)}, tight()), InputError);
    EXPECT_THROW(solve_radiation(F, area, std::vector{temp(0.0, 300.0), temp(0.5, 300.0)}, tight()), InputError);
    EXPECT_THROW(solve_radiation(F, area, std::vector{temp(1.5, 300.0), temp(0.5, 300.0)}, tight()), InputError);
    // Too few iterations: NotConvergedError (exit 5), never an answer.
    RadiateOptions o = tight();
    o.max_iterations = 1;
    o.restart = 1;
    EXPECT_THROW(solve_radiation(F, area, std::vector{temp(0.02, 1000.0), temp(0.02, 300.0)}, o), NotConvergedError);
}

TEST(Radiate, ConductancesTwoSurface) {
    // GR_12 = A1 / (1/ε1 + (A1/A2)(1/ε2 − 1)): the two-surface power over σ(T1⁴ − T2⁴).
    const CsrMatrix F = two_surface();
    const std::vector<double> area{kA1, kA2};
    const std::vector<std::uint32_t> object{0, 1};
    for (const Case c : {Case{0.6, 0.3, 1e-10}, Case{0.02, 0.02, 1e-8}}) {
        const ConductanceResult g = radiative_conductances(F, area, std::vector{c.e1, c.e2}, object, 2, tight());
        const double gr = kA1 / (1.0 / c.e1 + (kA1 / kA2) * (1.0 / c.e2 - 1.0));
        EXPECT_NEAR(g.gr[0][1], gr, c.tol * gr);
        std::cout << "[measured] GR eps " << c.e1 << "," << c.e2 << ": rel error " << std::abs(g.gr[0][1] - gr) / gr << ", "
                  << std::abs(g.gr[1][0] - gr) / gr << "\n";
        EXPECT_NEAR(g.gr[1][0], gr, c.tol * gr);
        EXPECT_LE(g.reciprocity_error, c.tol);
        EXPECT_LE(g.sum_rule_error, c.tol);
        EXPECT_EQ(g.solves, 2u);
        EXPECT_DOUBLE_EQ(g.emittance[0], c.e1 * kA1);
        // Sum rule: Σ_l GR_kl = ε_k A_k in a closed enclosure.
        EXPECT_NEAR(g.gr[1][0] + g.gr[1][1], c.e2 * kA2, c.tol * c.e2 * kA2);
    }
}

TEST(Radiate, ConductancesReciprocityAndSumRuleWithSky) {
    // Four patches, half of what leaves the last two escaping to the sky: F reciprocal by
    // construction (A_i F_ij = A_j F_ji: 1 × 0.1875 = 0.75 × 0.25), rows 0 and 1 losing 0.375 to the
    // sky. Objects {0}, {1, 2}, {3}.
    const CsrMatrix F = dense_to_csr({{0.0, 0.25, 0.1875, 0.1875},
                                      {0.25, 0.0, 0.1875, 0.1875},
                                      {0.25, 0.25, 0.0, 0.0},
                                      {0.25, 0.25, 0.0, 0.0}});
    const std::vector<double> area{1.0, 1.0, 0.75, 0.75};
    const std::vector<std::uint32_t> object{0, 1, 1, 2};
    const ConductanceResult g = radiative_conductances(F, area, std::vector{0.3, 0.9, 0.5, 0.1}, object, 3, tight());
    // F and A are exactly reciprocal: GR symmetric and Σ_l GR_kl + GR_k,sky = ε_k A_k, up to the
    // solve's error (cond ≤ 2/ε_min = 20, τ = 1e-13: 2e-12).
    EXPECT_GT(g.gr_sky[0], 0.1);
    EXPECT_LE(g.reciprocity_error, 1e-11);
    EXPECT_LE(g.sum_rule_error, 1e-11);
    for (int k = 0; k < 3; ++k)
        for (int l = 0; l < 3; ++l) EXPECT_NEAR(g.gr[k][l], g.gr[l][k], 1e-11 * (g.gr[k][l] + 1e-300));
    EXPECT_DOUBLE_EQ(g.emittance[1], 0.9 * 1.0 + 0.5 * 0.75);
}

TEST(Radiate, SurfacesCsv) {
    const std::string ok = "# comment\nobject,emissivity,temperature,heat_flux\ninner,0.5,300,\n\"outer, big\",1,,0\n";
    const auto lines = parse_surfaces_csv(ok, "s.csv");
    ASSERT_EQ(lines.size(), 2u);
    EXPECT_EQ(lines[1].object, "outer, big");
    EXPECT_EQ(lines[1].spec.condition, SurfaceCondition::HeatFlux);
    EXPECT_EQ(lines[1].line, 4u);
    const std::vector<std::string> objects{"inner", "outer, big", "lid"};
    EXPECT_THROW(surfaces_for_objects(objects, lines, "s.csv", std::nullopt), InputError);
    const auto specs = surfaces_for_objects(objects, lines, "s.csv", parse_default_surface("0.9,290"));
    EXPECT_DOUBLE_EQ(specs[2].value, 290.0);
    const auto message = [](const std::string& text) {
        try {
            parse_surfaces_csv(text, "s.csv");
        } catch (const InputError& e) {
            return std::string(e.what());
        }
        return std::string("accepted");
    };
    const std::string h = "object,emissivity,temperature,heat_flux\n";
    EXPECT_NE(message(h + "a,0,300,\n").find("s.csv:2: emissivity 0"), std::string::npos);
    EXPECT_NE(message(h + "a,1.2,300,\n").find("s.csv:2"), std::string::npos);
    EXPECT_NE(message(h + "a,0.5,300,10\n").find("s.csv:2: 'a' gives both"), std::string::npos);
    EXPECT_NE(message(h + "a,0.5,,\n").find("neither"), std::string::npos);
    EXPECT_NE(message(h + "a,0.5,-3,\n").find("s.csv:2: temperature -3"), std::string::npos);
    EXPECT_NE(message(h + "a,0.5,nan,\n").find("not a finite number"), std::string::npos);
    EXPECT_NE(message(h + "a,0.5,300x,\n").find("'300x'"), std::string::npos);
    EXPECT_NE(message(h + "a,0.5,300\n").find("3 fields"), std::string::npos);
    EXPECT_NE(message(h + "a,0.5,300,\n\na,0.5,300,\n").find("s.csv:4: object 'a' is listed again (first on line 2)"),
              std::string::npos);
    EXPECT_NE(message("a,0.5,300,\n").find("s.csv:1: the first line must be the header"), std::string::npos);
    EXPECT_NE(message("").find("empty"), std::string::npos);
    EXPECT_THROW(surfaces_for_objects(objects, parse_surfaces_csv(h + "nope,0.5,300,\n", "s.csv"), "s.csv", std::nullopt),
                 InputError);
    EXPECT_THROW(parse_default_surface("0.5"), InputError);
    EXPECT_THROW(parse_default_surface("0.5,-1"), InputError);
}

}  // namespace
}  // namespace ffcube
