// Spectral bands (solver/radiate.hpp): the blackbody fraction series against published values and
// an independent quadrature of Planck's law; band solves against the gray solve (one band, equal
// bands) and against the two-surface closed form applied band by band; the bands CSV's refusals.
//
// Tolerances. F here holds only float-exact values (0, 1/4, 3/4, 1/2, 1), so the only error is the
// solves' (τ = 1e-13, see test_radiate.cpp's header: ≤ 1e-10 relative in a flux for ε ≥ 0.3, 1e-8
// at ε = 0.02). The band sums add K such errors, each relative to its band's share: bounded by the
// same figure relative to the total when the bands' powers have one sign (they do here: T1 > T2).
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
constexpr double kInf = std::numeric_limits<double>::infinity();
constexpr double kPi = 3.14159265358979323846;

using test::dense_to_csr;

SurfaceSpec temp(double eps, double t) { return {eps, SurfaceCondition::Temperature, t}; }
SurfaceSpec flux(double eps, double q) { return {eps, SurfaceCondition::HeatFlux, q}; }

RadiateOptions tight() {
    RadiateOptions o;
    o.tolerance = 1e-13;
    o.outer_tolerance = 1e-12;
    return o;
}

// A BandModel by hand: edges and one row of emissivities per object.
BandModel model(std::vector<double> edges, std::vector<std::vector<double>> eps) {
    BandModel m;
    m.edges = std::move(edges);
    for (const auto& row : eps) m.emissivity.insert(m.emissivity.end(), row.begin(), row.end());
    return m;
}

// (15/π⁴) ∫_a^b u³/(e^u − 1) du by composite Simpson with 20000 intervals. The integrand is smooth
// (≈ u² near 0) with |f⁗| < 2 on u ≥ 0, so the error is below (b − a) h⁴ · 2/180 ≤ 1e-14 for
// b − a ≤ 20 (h ≤ 1e-3).
double planck_integral(double a, double b) {
    const auto f = [](double u) { return u == 0.0 ? 0.0 : u * u * u / std::expm1(u); };
    const int n = 20000;
    const double h = (b - a) / n;
    double s = f(a) + f(b);
    for (int k = 1; k < n; ++k) s += (k % 2 ? 4.0 : 2.0) * f(a + k * h);
    return 15.0 / (kPi * kPi * kPi * kPi) * s * h / 3.0;
}

TEST(RadiateBands, BlackbodyFractionMatchesPublishedTable) {
    // Published values of the blackbody radiation function (Incropera & DeWitt, Fundamentals of
    // Heat and Mass Transfer, Table 12.1; Siegel & Howell, Appendix A), as textbooks quote them, to
    // 3 decimals (4 at 2000 µm·K): each within half a unit of its last digit. (The tables' 6-decimal
    // entries differ among editions and C2 values by up to 4e-5; the quadrature test below is the
    // tight, independent check.)
    const std::pair<double, double> table[] = {{2000.0, 0.0667}, {2898.0, 0.250}, {4000.0, 0.481},
                                               {5000.0, 0.634},  {6000.0, 0.738}, {10000.0, 0.914}};
    for (const auto& [x, f] : table) {
        const double half_unit = x == 2000.0 ? 5e-5 : 5e-4;
        EXPECT_NEAR(blackbody_fraction(x), f, half_unit) << "lambda T = " << x;
    }
    EXPECT_EQ(blackbody_fraction(0.0), 0.0);
    EXPECT_EQ(blackbody_fraction(kInf), 1.0);
    EXPECT_THROW(blackbody_fraction(-1.0), InputError);
}

TEST(RadiateBands, BlackbodyFractionMatchesQuadratureOnBothSeries) {
    // Bands on both sides of the series' switch (ζ = c₂/λT = 2, λT ≈ 7194 µm·K) and across it:
    // F(x2) − F(x1) = (15/π⁴) ∫_{c₂/x2}^{c₂/x1} u³/(e^u − 1) du. Quadrature error ≤ 1e-14 (above),
    // the series' ≤ 1e-15 each: 1e-13.
    const double c2 = kSecondRadiationConstant;
    const std::pair<double, double> bands[] = {{800.0, 1500.0},  {1500.0, 3000.0}, {3000.0, 7000.0},
                                               {7000.0, 7400.0}, {5000.0, 20000.0}, {7300.0, 60000.0},
                                               {20000.0, 2e5}};
    double worst = 0.0;
    for (const auto& [x1, x2] : bands) {
        const double series = blackbody_fraction(x2) - blackbody_fraction(x1);
        const double quad = planck_integral(c2 / x2, c2 / x1);
        EXPECT_NEAR(series, quad, 1e-13) << x1 << " to " << x2;
        worst = std::max(worst, std::abs(series - quad));
    }
    // The part above λT = 1e5 (ζ < 0.144) against quadrature from 0: 1 − F(1e5).
    EXPECT_NEAR(1.0 - blackbody_fraction(1e5), planck_integral(0.0, c2 / 1e5), 1e-13);
    std::cout << "[measured] band fraction series vs Simpson: max |error| " << worst << "\n";
    // Complementary bands sum to 1: F(0→x) + F(x→∞) from the quadrature of the upper part (0 to
    // ζ = c₂/x, error ≤ 1e-14, ζ ≤ 20 here).
    for (const double x : {720.0, 2898.0, 7194.0, 7195.0, 30000.0}) {
        EXPECT_NEAR(blackbody_fraction(x) + planck_integral(0.0, c2 / x), 1.0, 1e-13) << x;
    }
}

TEST(RadiateBands, SlopeMatchesFiniteDifference) {
    // x F'(x) against a central difference of F with h = 1e-4 x: truncation (h²/6) x |F'''| and
    // rounding 1e-16 / 1e-4, both below 1e-8 (F's derivatives times x^k are O(1)).
    for (const double x : {600.0, 1500.0, 2898.0, 7194.0, 7195.0, 20000.0, 1e5}) {
        const double h = 1e-4 * x;
        const double fd = x * (blackbody_fraction(x + h) - blackbody_fraction(x - h)) / (2.0 * h);
        EXPECT_NEAR(blackbody_fraction_slope(x), fd, 1e-8) << x;
    }
}

// Two-surface enclosure (body 1 inside body 2, A1 = 1, A2 = 4), as in test_radiate.cpp.
constexpr double kA1 = 1.0, kA2 = 4.0;
CsrMatrix two_surface() { return dense_to_csr({{0.0, 1.0}, {kA1 / kA2, 1.0 - kA1 / kA2}}); }

// The two-surface closed form (Incropera eq. 13.25, F12 = 1) applied in every band: the bands do not
// exchange energy, so each is a gray two-surface enclosure with blackbody emission E_bk(T).
double banded_power(const BandModel& m, double t1, double t2) {
    double p = 0.0;
    for (std::uint32_t k = 0; k < m.bands(); ++k) {
        const auto ebk = [&](double t) {
            const double lo = m.edges[k] == 0.0 ? 0.0 : blackbody_fraction(m.edges[k] * t);
            const double hi = std::isinf(m.edges[k + 1]) ? 1.0 : blackbody_fraction(m.edges[k + 1] * t);
            return (hi - lo) * kSigma * std::pow(t, 4);
        };
        const double e1 = m.emissivity[k], e2 = m.emissivity[m.bands() + k];
        p += kA1 * (ebk(t1) - ebk(t2)) / (1.0 / e1 + (kA1 / kA2) * (1.0 / e2 - 1.0));
    }
    return p;
}

TEST(RadiateBands, OneBandIsTheGraySolveBitForBit) {
    const CsrMatrix F = two_surface();
    const std::vector<double> area{kA1, kA2};
    const std::vector<std::uint32_t> group{0, 1};
    const std::vector<SurfaceSpec> spec{temp(0.6, 1000.0), temp(0.3, 300.0)};
    const RadiateResult gray = solve_radiation(F, area, spec, tight());
    const RadiateResult band = solve_radiation_bands(F, area, spec, group, model({0.0, kInf}, {{0.6}, {0.3}}), tight());
    for (int i = 0; i < 2; ++i) {
        EXPECT_EQ(band.heat_flux[i], gray.heat_flux[i]);
        EXPECT_EQ(band.radiosity[i], gray.radiosity[i]);
        EXPECT_EQ(band.irradiation[i], gray.irradiation[i]);
    }
    EXPECT_EQ(band.power, gray.power);
    EXPECT_EQ(band.outer_iterations, 0u);
}

TEST(RadiateBands, EqualBandsGiveTheGrayAnswer) {
    // The triangular duct of test_radiate.cpp (two held walls, one reradiating) and the two-surface
    // enclosure with a heat-flux body: 1, 3 and 5 bands of equal emissivity. Summing the band
    // systems gives the gray system, and the outer iteration's gray Jacobian is then exact: after
    // one correction the flux residual is the solves' (≤ 1e-10 relative, header), so 1e-9.
    const CsrMatrix duct = dense_to_csr({{0.0, 0.25, 0.75}, {0.25, 0.0, 0.75}, {0.5, 0.5, 0.0}});
    const std::vector<double> duct_area{1.0, 1.0, 1.5};
    const std::vector<SurfaceSpec> duct_spec{temp(0.8, 800.0), temp(0.4, 400.0), flux(0.5, 0.0)};
    const std::vector<std::uint32_t> group{0, 1, 2};
    const RadiateResult gray = solve_radiation(duct, duct_area, duct_spec, tight());
    for (const std::vector<double>& edges :
         {std::vector<double>{0.0, kInf}, std::vector<double>{0.0, 4.0, kInf}, std::vector<double>{0.0, 2.0, 3.5, 9.0, 30.0, kInf}}) {
        const std::size_t K = edges.size() - 1;
        const BandModel m = model(edges, {std::vector<double>(K, 0.8), std::vector<double>(K, 0.4), std::vector<double>(K, 0.5)});
        const RadiateResult r = solve_radiation_bands(duct, duct_area, duct_spec, group, m, tight());
        SCOPED_TRACE(testing::Message() << K << " bands");
        for (int i = 0; i < 3; ++i) {
            EXPECT_NEAR(r.heat_flux[i], gray.heat_flux[i], 1e-9 * std::abs(gray.heat_flux[0]));
            EXPECT_NEAR(r.radiosity[i], gray.radiosity[i], 1e-9 * gray.radiosity[0]);
            // T from σT⁴ = J at the wall: dT/T = (1/4) dJ/J.
            EXPECT_NEAR(r.temperature[i], gray.temperature[i], 1e-9 * gray.temperature[i]);
        }
        EXPECT_LE(r.outer_iterations, 3u);  // a residual, one correction, a check (plus one for rounding)
        EXPECT_LE(r.balance_error, 1e-9);
        std::cout << "[measured] " << K << " equal bands vs gray: wall T " << r.temperature[2] << " vs "
                  << gray.temperature[2] << ", outer iterations " << r.outer_iterations << "\n";
    }
}

TEST(RadiateBands, TwoSurfaceNonGrayMatchesTheBandByBandClosedForm) {
    const CsrMatrix F = two_surface();
    const std::vector<double> area{kA1, kA2};
    const std::vector<std::uint32_t> group{0, 1};
    struct Case {
        BandModel m;
        double tol;  // the header's: 1e-10 relative for ε ≥ 0.1 (cond ≤ 2/ε_min), 1e-8 at 0.02
    };
    const Case cases[] = {
        {model({0.0, 3.0, 8.0, kInf}, {{0.2, 0.9, 0.6}, {0.8, 0.3, 0.5}}), 1e-9},
        {model({0.0, 2.5, 6.0, 25.0, kInf}, {{0.9, 0.1, 0.5, 1.0}, {0.3, 1.0, 0.7, 0.2}}), 1e-9},
        {model({0.0, 5.0, kInf}, {{0.02, 0.05}, {0.02, 0.03}}), 1e-8},
    };
    for (const Case& c : cases) {
        const double t1 = 1000.0, t2 = 300.0;
        const double p = banded_power(c.m, t1, t2);
        const RadiateResult r = solve_radiation_bands(F, area, std::vector{temp(0.5, t1), temp(0.5, t2)}, group, c.m, tight());
        EXPECT_NEAR(r.heat_flux[0] * kA1, p, c.tol * p);
        EXPECT_NEAR(r.heat_flux[1] * kA2, -p, c.tol * p);
        std::cout << "[measured] two-surface, " << c.m.bands() << " bands: rel error " << std::abs(r.heat_flux[0] * kA1 - p) / p
                  << "\n";
        // Body 2 given the flux it takes at 300 K: the outer iteration brings T2 back. It stops at a
        // flux residual ≤ outer_tolerance × σT1⁴; dT2 = dq2 A2 / |dp/dT2| (dp/dT2 by a central
        // difference of the closed form, accurate to 1e-6 relative), doubled for the inner solves.
        const double dpdt = (banded_power(c.m, t1, t2 + 0.01) - banded_power(c.m, t1, t2 - 0.01)) / 0.02;
        const double tol_t = 2.0 * tight().outer_tolerance * kSigma * std::pow(t1, 4) * kA2 / std::abs(dpdt) +
                             c.tol * t2;
        const RadiateResult s =
            solve_radiation_bands(F, area, std::vector{temp(0.5, t1), flux(0.5, -p / kA2)}, group, c.m, tight());
        EXPECT_NEAR(s.temperature[1], t2, tol_t);
        EXPECT_NEAR(s.heat_flux[0] * kA1, p, c.tol * p + std::abs(dpdt) * tol_t);
        EXPECT_GE(s.outer_iterations, 2u);
        std::cout << "[measured]   given flux: T2 error " << std::abs(s.temperature[1] - t2) << " K (bound " << tol_t
                  << "), " << s.outer_iterations << " outer iterations\n";
    }
}

// An open scene: two facing patches that see each other with F = 1/2 and the sky with the other
// half, the sky at 250 K. Per band the 2 × 2 system J_i − (1 − ε_ik) F J_j = ε_ik E_bk(T_i) +
// (1 − ε_ik) F_sky E_bk(T_sky) is solved by hand (Cramer); q_i = Σ_k ε_ik (E_bk(T_i) − G_ik). The
// energy balance: Σ A q equals the net exchange with the sky, to 1e-9 of the powers (issue 38).
TEST(RadiateBands, OpenScenePerBandAgainstCramerAndTheSkyBalance) {
    const CsrMatrix F = dense_to_csr({{0.0, 0.5}, {0.5, 0.0}});
    const BandModel m = model({0.0, 4.0, 12.0, kInf}, {{0.3, 0.8, 0.6}, {0.9, 0.2, 0.05}});
    const double t[2] = {700.0, 400.0}, tsky = 250.0;
    RadiateOptions o = tight();
    o.sky_temperature = tsky;
    const RadiateResult r = solve_radiation_bands(F, std::vector{1.0, 1.0}, std::vector{temp(0.5, t[0]), temp(0.5, t[1])},
                                                  std::vector<std::uint32_t>{0, 1}, m, o);
    double q[2] = {0.0, 0.0}, scale = 0.0;
    for (std::uint32_t k = 0; k < 3; ++k) {
        const auto ebk = [&](double temp_k) {
            const double lo = m.edges[k] == 0.0 ? 0.0 : blackbody_fraction(m.edges[k] * temp_k);
            const double hi = std::isinf(m.edges[k + 1]) ? 1.0 : blackbody_fraction(m.edges[k + 1] * temp_k);
            return (hi - lo) * kSigma * std::pow(temp_k, 4);
        };
        const double e0 = m.emissivity[k], e1 = m.emissivity[3 + k];
        const double b0 = e0 * ebk(t[0]) + (1 - e0) * 0.5 * ebk(tsky), b1 = e1 * ebk(t[1]) + (1 - e1) * 0.5 * ebk(tsky);
        // [1, −(1−e0)/2; −(1−e1)/2, 1] J = b.
        const double a01 = -(1 - e0) * 0.5, a10 = -(1 - e1) * 0.5, det = 1.0 - a01 * a10;
        const double j0 = (b0 - a01 * b1) / det, j1 = (b1 - a10 * b0) / det;
        q[0] += e0 * (ebk(t[0]) - (0.5 * j1 + 0.5 * ebk(tsky)));
        q[1] += e1 * (ebk(t[1]) - (0.5 * j0 + 0.5 * ebk(tsky)));
        scale = std::max(scale, j0);
    }
    // The solves' 1e-10 (header) of J: fluxes within 1e-10 × J_max per band, 3 bands.
    for (int i = 0; i < 2; ++i) EXPECT_NEAR(r.heat_flux[i], q[i], 3e-10 * scale) << i;
    EXPECT_GT(std::abs(r.sky), 0.1 * r.absolute_power);  // the sky takes a real share
    EXPECT_LE(r.balance_error, 1e-9);
    std::cout << "[measured] open two-plate, 3 bands: q error " << std::abs(r.heat_flux[0] - q[0]) << ", "
              << std::abs(r.heat_flux[1] - q[1]) << " W/m2; balance error " << r.balance_error << "\n";
}

TEST(RadiateBands, OuterIterationThatCannotConvergeIsRefused) {
    // Body 2 asked to absorb more than everything body 1 can send: it would need T < 0 K; the iteration
    // holds it at 0 K and stops at the limit: NotConvergedError, never a result.
    const CsrMatrix F = two_surface();
    const BandModel m = model({0.0, 5.0, kInf}, {{0.5, 0.9}, {0.3, 0.6}});
    RadiateOptions o = tight();
    o.max_outer_iterations = 8;
    EXPECT_THROW(solve_radiation_bands(F, std::vector{kA1, kA2}, std::vector{temp(0.5, 500.0), flux(0.5, -1e6)}, std::vector<std::uint32_t>{0, 1}, m, o), NotConvergedError);
}

TEST(RadiateBands, BandsCsv) {
    const std::vector<std::string> objects{"hot", "cold", "wall"};
    const auto parse = [&](const std::string& text) { return parse_bands_csv(text, "B.csv"); };
    const std::string header = "object,lambda_min_um,lambda_max_um,emissivity\n";
    const std::vector<NamedBand> lines = parse(header + "# comment\nhot,0,4,0.2\nhot,4,inf,0.9\n\ncold,3,8,0.5\n");
    ASSERT_EQ(lines.size(), 3u);
    EXPECT_TRUE(std::isinf(lines[1].lambda_max));
    EXPECT_EQ(lines[2].line, 6u);
    // The partition: 0, 3, 4, 8, inf. 'cold' takes its gray emissivity (0.7) outside [3, 8]; 'wall' has
    // no band and is gray (0.1) everywhere.
    const BandModel m = bands_for_objects(objects, lines, "B.csv", std::vector<double>{0.6, 0.7, 0.1});
    ASSERT_EQ(m.edges, (std::vector<double>{0.0, 3.0, 4.0, 8.0, kInf}));
    EXPECT_EQ(m.emissivity, (std::vector<double>{0.2, 0.2, 0.9, 0.9, 0.7, 0.5, 0.5, 0.7, 0.1, 0.1, 0.1, 0.1}));

    const auto refused = [&](const std::string& text, const std::string& needle) {
        try {
            const auto l = parse(text);
            bands_for_objects(objects, l, "B.csv", std::vector<double>{0.6, 0.7, 0.1});
            ADD_FAILURE() << "accepted: " << text;
        } catch (const InputError& e) {
            EXPECT_NE(std::string(e.what()).find(needle), std::string::npos) << e.what();
        }
    };
    refused(header + "hot,0,4,0.2\nhot,3,inf,0.9\n", "B.csv:3: band [3, inf] um of 'hot' overlaps its band [0, 4] um on line 2");
    refused(header + "hot,5,4,0.2\n", "B.csv:2: band [5, 4] um of 'hot' is inverted");
    refused(header + "hot,4,4,0.2\n", "B.csv:2: band [4, 4] um of 'hot' is inverted or empty");
    refused(header + "hot,-1,4,0.2\n", "B.csv:2: lambda_min_um -1 must be >= 0");
    refused(header + "hot,0,4,1.5\n", "B.csv:2: emissivity 1.5 must be in (0, 1]");
    refused(header + "hot,0,4,0\n", "B.csv:2: emissivity 0 must be in (0, 1]");
    refused(header + "hot,0,4\n", "B.csv:2: 3 fields");
    refused(header + "hot,0,,0.5\n", "B.csv:2: 'hot': every field is required");
    refused(header + "hot,0,x,0.5\n", "B.csv:2: lambda_max_um 'x' is not a finite number");
    refused(header + "\nlid,0,4,0.5\n", "B.csv:3: the scene has no object 'lid'");
    refused("object,emissivity\n", "B.csv:1: the first line must be the header");
    refused("", "B.csv: empty");
}

}  // namespace
}  // namespace ffcube
