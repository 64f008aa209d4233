// Patch level: a closed unit box, each wall 4 × 4 patches (96), exact F from closed forms (Howell
// C-12 for opposite walls; C-14 with Hottel's superposition for adjacent ones), a mix of temperature
// and heat-flux walls. solve_radiation (GMRES on the rows) against an independent dense solve
// (Gaussian elimination with partial pivoting of the same 96 equations), the energy balance, and
// the stiff case ε = 0.02 on every wall.
#include <gtest/gtest.h>

#include <array>
#include <limits>
#include <cmath>
#include <iostream>
#include <vector>

#include "ffcube/reference/closed_forms.hpp"
#include "ffcube/solver/radiate.hpp"

namespace ffcube {
namespace {

constexpr int kCells = 4;
constexpr double kSigma = 5.670374419e-8;

// Wall w = 2 a + s: the plane x_a = s (a = 0, 1, 2; s = 0, 1), facing into the box; patch (w, iu,
// iv) covers [iu/4, (iu+1)/4] along axis u = (a+1)%3 and [iv/4, (iv+1)/4] along v = (a+2)%3.
struct PatchBox {
    int axis, side;
    std::array<double, 3> lo, hi;  // extents (lo = hi = side along the normal axis)
};

std::vector<PatchBox> box_patches() {
    std::vector<PatchBox> p;
    for (int w = 0; w < 6; ++w)
        for (int iu = 0; iu < kCells; ++iu)
            for (int iv = 0; iv < kCells; ++iv) {
                PatchBox b{w / 2, w % 2, {}, {}};
                const int u = (b.axis + 1) % 3, v = (b.axis + 2) % 3;
                b.lo[b.axis] = b.hi[b.axis] = b.side;
                b.lo[u] = double(iu) / kCells;
                b.hi[u] = double(iu + 1) / kCells;
                b.lo[v] = double(iv) / kCells;
                b.hi[v] = double(iv + 1) / kCells;
                p.push_back(b);
            }
    return p;
}

// A F between [0, s] × [0, w] and [0, s] × [0, h], perpendicular with a common edge of length s.
double common_edge(double s, double w, double h) {
    if (s <= 0.0 || w <= 0.0 || h <= 0.0) return 0.0;
    return s * w * ff_perpendicular_rectangles_common_edge(s, w, h);
}

// A_p F_pq for perpendicular strips at distances [y1, y2] and [η1, η2] from the common line, spans
// [a, b] and [c, d] along it. A F is bilinear in the two areas (Hottel's algebra): over the
// distances by inclusion–exclusion from strips that reach the line, and along the line, since the
// kernel depends on x − x' only, Q([a,b],[c,d]) = ½[K(b−c) − K(a−c) − K(b−d) + K(a−d)] with
// K(s) = A F of the two strips over a common span [0, |s|] (Q([0,s],[0,s]) = K(s)).
double perpendicular(double y1, double y2, double e1, double e2, double a, double b, double c, double d) {
    double sum = 0.0;
    for (const auto& [y, sy] : {std::pair{y2, 1.0}, {y1, -1.0}})
        for (const auto& [e, se] : {std::pair{e2, 1.0}, {e1, -1.0}}) {
            const auto k = [&](double s) { return common_edge(std::abs(s), y, e); };
            sum += sy * se * 0.5 * (k(b - c) - k(a - c) - k(b - d) + k(a - d));
        }
    return sum;
}

std::vector<std::vector<double>> exact_box_f(const std::vector<PatchBox>& p) {
    const std::size_t n = p.size();
    const double area = 1.0 / (kCells * kCells);
    std::vector<std::vector<double>> f(n, std::vector<double>(n, 0.0));
    for (std::size_t i = 0; i < n; ++i)
        for (std::size_t j = 0; j < n; ++j) {
            const PatchBox &P = p[i], &Q = p[j];
            if (P.axis == Q.axis) {
                if (P.side == Q.side) continue;  // the same wall: flat, F = 0
                const int u = (P.axis + 1) % 3, v = (P.axis + 2) % 3;
                f[i][j] = ff_parallel_rectangles_offset(P.lo[u], P.hi[u], P.lo[v], P.hi[v], Q.lo[u], Q.hi[u], Q.lo[v],
                                                        Q.hi[v], 1.0);
            } else {
                const int a = P.axis, b = Q.axis, e = 3 - a - b;  // e: along the common line x_a = s_a, x_b = s_b
                // Distances from the line: P's along axis b from s_b, Q's along axis a from s_a.
                double y1 = std::abs(P.lo[b] - Q.side), y2 = std::abs(P.hi[b] - Q.side);
                double e1 = std::abs(Q.lo[a] - P.side), e2 = std::abs(Q.hi[a] - P.side);
                if (y1 > y2) std::swap(y1, y2);
                if (e1 > e2) std::swap(e1, e2);
                f[i][j] = perpendicular(y1, y2, e1, e2, P.lo[e], P.hi[e], Q.lo[e], Q.hi[e]) / area;
            }
        }
    return f;
}

// Dense Gaussian elimination with partial pivoting: A x = b.
std::vector<double> dense_solve(std::vector<std::vector<double>> a, std::vector<double> b) {
    const std::size_t n = b.size();
    for (std::size_t k = 0; k < n; ++k) {
        std::size_t piv = k;
        for (std::size_t i = k + 1; i < n; ++i)
            if (std::abs(a[i][k]) > std::abs(a[piv][k])) piv = i;
        std::swap(a[k], a[piv]);
        std::swap(b[k], b[piv]);
        for (std::size_t i = k + 1; i < n; ++i) {
            const double m = a[i][k] / a[k][k];
            for (std::size_t j = k; j < n; ++j) a[i][j] -= m * a[k][j];
            b[i] -= m * b[k];
        }
    }
    std::vector<double> x(n);
    for (std::size_t i = n; i-- > 0;) {
        double s = b[i];
        for (std::size_t j = i + 1; j < n; ++j) s -= a[i][j] * x[j];
        x[i] = s / a[i][i];
    }
    return x;
}

struct Wall {
    double emissivity;
    SurfaceCondition condition;
    double value;
};

TEST(RadiateBox, PerPatchFluxMatchesDenseSolveOnExactF) {
    const std::vector<PatchBox> patches = box_patches();
    const std::size_t n = patches.size();
    const std::vector<std::vector<double>> exact = exact_box_f(patches);
    // The closed forms are right and put together right: every row of the closed box sums to 1
    // (the closed forms are accurate to ~1e-14; 96 terms), and A_i F_ij = A_j F_ji.
    for (std::size_t i = 0; i < n; ++i) {
        double s = 0.0;
        for (std::size_t j = 0; j < n; ++j) {
            s += exact[i][j];
            EXPECT_NEAR(exact[i][j], exact[j][i], 1e-13);
        }
        EXPECT_NEAR(s, 1.0, 1e-12) << "row " << i;
    }
    // The rows as float (what a CsrMatrix holds), symmetrised before rounding so that the float rows
    // stay exactly reciprocal (equal areas: F_ij = F_ji); they then sum to 1 within float rounding
    // (~1e-7, below the open-scene threshold 1e-6). The dense solve uses the same float values, so
    // both solve one system and differ by the solvers only.
    CsrMatrix F(static_cast<std::uint32_t>(n));
    std::vector<std::vector<double>> fd(n, std::vector<double>(n, 0.0));
    for (std::size_t i = 0; i < n; ++i) {
        std::vector<std::uint32_t> col;
        std::vector<float> val;
        for (std::size_t j = 0; j < n; ++j)
            if (exact[i][j] > 0.0) {
                col.push_back(static_cast<std::uint32_t>(j));
                val.push_back(static_cast<float>(0.5 * (exact[i][j] + exact[j][i])));
                fd[i][j] = double(val.back());
            }
        F.append_row(col, val);
    }
    const std::vector<double> area(n, 1.0 / (kCells * kCells));
    const auto T = SurfaceCondition::Temperature;
    const auto Q = SurfaceCondition::HeatFlux;
    // Walls x0, x1, y0, y1, z0, z1: two held, a heater, an adiabatic polished wall, two adiabatic.
    const std::vector<std::vector<Wall>> cases = {
        {{0.9, T, 600.0}, {0.3, T, 300.0}, {0.7, Q, 2000.0}, {0.05, Q, 0.0}, {0.5, Q, 0.0}, {1.0, Q, 0.0}},
        {{0.02, T, 600.0}, {0.02, T, 300.0}, {0.02, Q, 500.0}, {0.02, Q, 0.0}, {0.02, Q, 0.0}, {0.02, Q, 0.0}},
        {{0.02, T, 600.0}, {0.02, T, 300.0}, {0.02, T, 450.0}, {0.02, T, 350.0}, {0.02, T, 400.0}, {0.02, T, 500.0}},
    };
    for (const auto& walls : cases) {
        std::vector<SurfaceSpec> spec(n);
        for (std::size_t i = 0; i < n; ++i) {
            const Wall& w = walls[2 * patches[i].axis + patches[i].side];
            spec[i] = {w.emissivity, w.condition, w.value};
        }
        RadiateOptions o;
        o.tolerance = 1e-12;
        const RadiateResult r = solve_radiation(F, area, spec, o);
        // The dense system, written out (docs/radiate.md): T given: J_i − (1 − ε_i) Σ F_ij J_j = ε_i σT_i⁴;
        // q given: J_i − Σ F_ij J_j = q_i. Then G = F J, q = ε(σT⁴ − G) where T is given.
        std::vector<std::vector<double>> a(n, std::vector<double>(n, 0.0));
        std::vector<double> b(n);
        for (std::size_t i = 0; i < n; ++i) {
            const bool held = spec[i].condition == T;
            const double c = held ? 1.0 - spec[i].emissivity : 1.0;
            for (std::size_t j = 0; j < n; ++j) a[i][j] = (i == j ? 1.0 : 0.0) - c * fd[i][j];
            b[i] = held ? spec[i].emissivity * kSigma * std::pow(spec[i].value, 4) : spec[i].value;
        }
        const std::vector<double> j = dense_solve(a, b);
        // Tolerance: GMRES stops at ‖b − AJ‖ ≤ 1e-12 ‖b‖; J's relative error ≤ cond(A) 1e-12 ≤
        // (2/ε_min) 1e-12 = 1e-10 at ε = 0.02 (test_radiate.cpp's header), the elimination's ~1e-14; a
        // flux is a difference of J-sized terms, ε(σT⁴ − G) with G ≤ J_max: error ≤ 1e-10 J_max.
        // Relative to the largest |q| (≥ 1e-2 J_max in these cases): 1e-8 — inside the 1e-5.
        double jmax = 0.0, qmax = 0.0, worst = 0.0;
        for (std::size_t i = 0; i < n; ++i) jmax = std::max(jmax, std::abs(j[i]));
        std::vector<double> qd(n);
        for (std::size_t i = 0; i < n; ++i) {
            double g = 0.0;
            for (std::size_t k = 0; k < n; ++k) g += fd[i][k] * j[k];
            qd[i] = spec[i].condition == T ? spec[i].emissivity * (kSigma * std::pow(spec[i].value, 4) - g) : spec[i].value;
            qmax = std::max(qmax, std::abs(qd[i]));
            if (spec[i].condition == Q) {  // the solved temperature: σT⁴ = G + q/ε
                const double td = std::pow((g + spec[i].value / spec[i].emissivity) / kSigma, 0.25);
                EXPECT_NEAR(r.temperature[i], td, 1e-10 * td * 2.0 / spec[i].emissivity) << "patch " << i;
            }
        }
        ASSERT_GT(qmax, 1e-2 * jmax);
        for (std::size_t i = 0; i < n; ++i) {
            EXPECT_NEAR(r.heat_flux[i], qd[i], 1e-8 * qmax) << "patch " << i;
            EXPECT_NEAR(r.radiosity[i], j[i], 1e-10 * jmax) << "patch " << i;
            worst = std::max(worst, std::abs(r.heat_flux[i] - qd[i]) / qmax);
        }
        // Energy: with reciprocal rows Σ A q equals what leaks through the rows' sums (Σ A F_sky J, to
        // a sky at 0 K) exactly but for the solve: 1e-9 of Σ A|q|. The leak itself is the float
        // rounding of the rows (≤ 96 × 6e-8 of J_max per patch).
        EXPECT_LE(r.balance_error, 1e-9);
        EXPECT_NEAR(r.power, r.sky, 1e-9 * r.absolute_power);
        EXPECT_LE(std::abs(r.sky), 96 * 6e-8 * jmax * 6.0);
        std::cout << "[measured] 4x4 box, eps_min " << r.min_emissivity << ": max |q - q_dense| / max|q| " << worst
                  << ", balance error " << r.balance_error << ", " << r.iterations << " GMRES products\n";
    }
}

// Same input, same output for any thread count: the product with the rows is split over threads
// from a million nonzeros; each g_i is one row's sum in one order, so the bits must not change.
// 1,100 patches that all see each other (1.2 M nonzeros), pseudo-random rows summing to 1 (within
// float rounding, below the open-scene threshold), mixed conditions, and the band path too.
TEST(RadiateBox, SameBitsForAnyThreadCount) {
    const std::uint32_t n = 1100;
    CsrMatrix F(n);
    std::uint64_t state = 12345;
    const auto next = [&] {  // xorshift64*
        state ^= state >> 12;
        state ^= state << 25;
        state ^= state >> 27;
        return double((state * 2685821657736338717ull) >> 11) / double(1ull << 53);
    };
    for (std::uint32_t i = 0; i < n; ++i) {
        std::vector<std::uint32_t> col;
        std::vector<double> w;
        double sum = 0.0;
        for (std::uint32_t j = 0; j < n; ++j)
            if (j != i) {
                col.push_back(j);
                w.push_back(0.5 + next());
                sum += w.back();
            }
        std::vector<float> val;
        for (const double x : w) val.push_back(static_cast<float>(x / sum));
        F.append_row(col, val);
    }
    ASSERT_GT(F.nnz(), 1000000u);
    std::vector<SurfaceSpec> spec(n);
    for (std::uint32_t i = 0; i < n; ++i)
        spec[i] = i % 3 == 0 ? SurfaceSpec{0.3 + 0.5 * next(), SurfaceCondition::HeatFlux, 0.0}
                             : SurfaceSpec{0.05 + 0.9 * next(), SurfaceCondition::Temperature, 300.0 + 400.0 * next()};
    const std::vector<double> area(n, 1.0);
    std::vector<std::uint32_t> group(n);
    for (std::uint32_t i = 0; i < n; ++i) group[i] = i % 2;
    BandModel bands;
    bands.edges = {0.0, 5.0, std::numeric_limits<double>::infinity()};
    bands.emissivity = {0.3, 0.9, 0.7, 0.2};
    RadiateOptions one;
    one.threads = 1;
    const RadiateResult gray1 = solve_radiation(F, area, spec, one);
    const RadiateResult band1 = solve_radiation_bands(F, area, spec, group, bands, one);
    for (const unsigned t : {2u, 3u}) {
        RadiateOptions o;
        o.threads = t;
        const RadiateResult gray = solve_radiation(F, area, spec, o);
        const RadiateResult band = solve_radiation_bands(F, area, spec, group, bands, o);
        EXPECT_EQ(gray.radiosity, gray1.radiosity) << t << " threads";
        EXPECT_EQ(gray.temperature, gray1.temperature) << t << " threads";
        EXPECT_EQ(band.heat_flux, band1.heat_flux) << t << " threads";
        EXPECT_EQ(band.temperature, band1.temperature) << t << " threads";
    }
}

}  // namespace
}  // namespace ffcube
