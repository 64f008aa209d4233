// Shortwave with reflections (solver/shortwave.hpp): the sweeps against a dense LU solve of the
// same system, the energy balance, thread-count independence, and the input files' refusals.
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "ffcube/core/error.hpp"
#include "ffcube/solver/linear.hpp"
#include "ffcube/solver/shortwave.hpp"

namespace ffcube {
namespace {

// A random sparse n × n F (not reciprocal; F_ii = 0), rows summing to at most `max_row_sum`.
CsrMatrix random_rows(std::uint32_t n, std::uint32_t per_row, double max_row_sum, std::uint32_t seed) {
    std::mt19937 rng(seed);
    std::uniform_int_distribution<std::uint32_t> pick(0, n - 1);
    std::uniform_real_distribution<double> u(0.05, 1.0);
    CsrMatrix F(n);
    for (std::uint32_t i = 0; i < n; ++i) {
        std::vector<std::pair<std::uint32_t, double>> e;
        for (std::uint32_t k = 0; k < per_row; ++k) {
            const std::uint32_t j = pick(rng);
            if (j == i) continue;
            bool dup = false;
            for (const auto& x : e) dup = dup || x.first == j;
            if (!dup) e.emplace_back(j, u(rng));
        }
        std::sort(e.begin(), e.end());
        double sum = 0.0;
        for (const auto& x : e) sum += x.second;
        const double scale = max_row_sum * u(rng) / std::max(sum, 1e-300);
        SparseRow row;
        for (const auto& x : e) {
            row.col.push_back(x.first);
            row.val.push_back(x.second * scale);
        }
        F.append_row(row);
    }
    return F;
}

std::string name_of(std::uint32_t i) { return "patch " + std::to_string(i); }

TEST(Shortwave, MatchesADenseSolveOfTheSameSystem) {
    const std::uint32_t n = 40, k = 3;
    const CsrMatrix F = random_rows(n, 12, 0.95, 7);
    std::mt19937 rng(11);
    std::uniform_real_distribution<double> u(0.0, 1.0);
    std::vector<double> albedo(n), Q(n * k);
    for (double& a : albedo) a = 0.9 * u(rng);
    for (double& q : Q) q = 1000.0 * u(rng);
    const ShortwaveSystem s = make_shortwave_system(F, albedo, name_of);
    ShortwaveControl control;
    control.tolerance = 1e-13;
    const ShortwaveSolution x = solve_shortwave(s, Q, k, control);

    // Dense: (I − diag(ρ) Fᵀ) P = ρ Q, then R = Fᵀ P.
    DenseMatrix A(n);
    for (std::uint32_t i = 0; i < n; ++i) {
        A(i, i) = 1.0;
        for (std::uint32_t j = 0; j < n; ++j) A(i, j) -= albedo[i] * F.at(j, i);
    }
    std::vector<std::uint32_t> perm;
    lu_factor(A, perm, "test");
    std::vector<double> scratch(n);
    for (std::uint32_t c = 0; c < k; ++c) {
        std::vector<double> P(n);
        double total = 0.0;
        for (std::uint32_t i = 0; i < n; ++i) {
            P[i] = albedo[i] * Q[i * k + c];
            total += Q[i * k + c];
        }
        lu_solve(A, perm, P, scratch);
        double absorbed = 0.0;
        for (std::uint32_t i = 0; i < n; ++i) {
            double R = 0.0;
            for (std::uint32_t j = 0; j < n; ++j) R += F.at(j, i) * P[j];
            // The sweeps stop when a sweep changes Σ|R| by ≤ 1e-13 Σ Q; the rest of the series is at
            // most that × c/(1 − c) with c ≤ 0.9 · 0.95 (≈ 6e-13 Σ Q), and LU on a system this well
            // conditioned (‖A⁻¹‖₁ ≤ 1/(1 − c) < 7) adds ~1e-14: 1e-11 × Σ Q per entry is safe.
            EXPECT_NEAR(x.reflected[i * k + c], R, 1e-11 * total) << "patch " << i << " rhs " << c;
            absorbed += x.absorbed[i * k + c];
        }
        // Balance: shortwave.cpp bounds it by the last change, ≤ 1e-13 Σ Q (plus rounding of n terms).
        EXPECT_NEAR(absorbed + x.escaped[c], total, 1e-12 * total) << "rhs " << c;
    }
}

TEST(Shortwave, TheSameBitsForOneOrManyThreads) {
    const std::uint32_t n = 1300, k = 21;  // 6 groups of 4 columns: the threads really split them
    const CsrMatrix F = random_rows(n, 30, 0.9, 3);
    std::vector<double> albedo(n, 0.35), Q(n * k);
    for (std::size_t x = 0; x < Q.size(); ++x) Q[x] = static_cast<double>((x * 2654435761u) % 1000);
    const ShortwaveSystem s = make_shortwave_system(F, albedo, name_of);
    ShortwaveControl one, four;
    one.threads = 1;
    four.threads = 4;
    const ShortwaveSolution a = solve_shortwave(s, Q, k, one), b = solve_shortwave(s, Q, k, four);
    EXPECT_EQ(a.iterations, b.iterations);
    EXPECT_EQ(a.reflected, b.reflected);
    EXPECT_EQ(a.absorbed, b.absorbed);
    EXPECT_EQ(a.escaped, b.escaped);
}

// More than 65,536 patches: the columns stay in 32 bits (16 bits below, as in the tests above).
// Checked against the equations themselves, recomputed here from F: R_i = Σ_j F_ji P_j with
// P_j = ρ_j (Q_j + R_j). The answer's R' = Fᵀ P comes from the last sweep's P; P' = ρ (Q + R')
// differs from P by ρ |R' − R| entrywise, so Σ_i |(Fᵀ P')_i − R'_i| ≤ max_j ρ_j Σ_i F_ji · Σ|R' − R|
// ≤ contraction × change × Σ Q: asserted with change × Σ Q (contraction < 1) plus 1e-12 Σ Q of
// rounding. The balance is bounded by the same change (shortwave.cpp).
TEST(Shortwave, MoreThan65536PatchesKeep32BitColumnsAndSolveTheEquations) {
    const std::uint32_t n = 70000, k = 2;
    const CsrMatrix F = random_rows(n, 3, 0.9, 13);
    std::vector<double> albedo(n, 0.4), Q(std::size_t(n) * k);
    for (std::size_t x = 0; x < Q.size(); ++x) Q[x] = static_cast<double>((x * 2654435761u) % 1000);
    const ShortwaveSystem s = make_shortwave_system(F, albedo, name_of);
    EXPECT_TRUE(s.t_col16.empty());
    EXPECT_EQ(s.t_col.size(), F.nnz());
    EXPECT_FALSE(make_shortwave_system(random_rows(100, 5, 0.9, 1), std::vector<double>(100, 0.4), name_of).t_col16.empty());
    const ShortwaveSolution x = solve_shortwave(s, Q, k);
    for (std::uint32_t c = 0; c < k; ++c) {
        std::vector<double> R(n, 0.0);
        double total = 0.0, absorbed = 0.0, residual = 0.0;
        for (std::uint32_t j = 0; j < n; ++j) {
            const double P = albedo[j] * (Q[std::size_t(j) * k + c] + x.reflected[std::size_t(j) * k + c]);
            const RowView row = F.row(j);
            for (std::size_t e = 0; e < row.col.size(); ++e) R[row.col[e]] += static_cast<double>(row.val[e]) * P;
            total += Q[std::size_t(j) * k + c];
            absorbed += x.absorbed[std::size_t(j) * k + c];
        }
        for (std::uint32_t i = 0; i < n; ++i) residual += std::abs(R[i] - x.reflected[std::size_t(i) * k + c]);
        EXPECT_LE(residual, (x.change + 1e-12) * total) << "rhs " << c;
        EXPECT_NEAR(absorbed + x.escaped[c], total, (x.change + 1e-12) * total) << "rhs " << c;
    }
}

TEST(Shortwave, NoReflectorMeansNothingReflected) {
    // Albedo 0 everywhere: the closed form is R = 0, absorbed = Q, escaped = 0.
    const CsrMatrix F = random_rows(20, 6, 0.9, 5);
    const ShortwaveSystem s = make_shortwave_system(F, std::vector<double>(20, 0.0), name_of);
    std::vector<double> Q(20, 3.0);
    const ShortwaveSolution x = solve_shortwave(s, Q, 1);
    for (std::uint32_t i = 0; i < 20; ++i) {
        EXPECT_EQ(x.reflected[i], 0.0);
        EXPECT_EQ(x.absorbed[i], 3.0);
    }
    EXPECT_EQ(x.escaped[0], 0.0);
}

TEST(Shortwave, RefusesAlbedoOutsideItsRangeAndRowsThatWouldNotConverge) {
    const CsrMatrix F = random_rows(10, 4, 0.9, 9);
    for (const double bad : {1.0, -0.1, std::nan("")}) {
        std::vector<double> a(10, 0.2);
        a[4] = bad;
        try {
            make_shortwave_system(F, a, name_of);
            FAIL() << bad;
        } catch (const InputError& e) {
            EXPECT_NE(std::string(e.what()).find("patch 4: albedo"), std::string::npos) << e.what();
        }
    }
    // Two patches that see only each other with F = 1.25 (no form-factor matrix has that).
    CsrMatrix G(2);
    G.append_row(SparseRow{{1}, {1.25}});
    G.append_row(SparseRow{{0}, {1.25}});
    EXPECT_THROW(make_shortwave_system(G, {0.9, 0.9}, name_of), InputError);
}

std::string message_of(const std::function<void()>& f) {
    try {
        f();
    } catch (const InputError& e) {
        return e.what();
    }
    return "(no error)";
}

TEST(SunSeries, ReadsBothHeadersAndTheirDirections) {
    const auto a = parse_sun_series(
        "time,azimuth,elevation,direct_normal_irradiance,diffuse_horizontal_irradiance\r\n"
        "# a comment\n\n2024-06-21T12:00,180,60,800,100\n06:00,90,0,0,5\n",
        "sun.csv");
    ASSERT_EQ(a.size(), 2u);
    // Azimuth 180 (south, −y), elevation 60: (0, −cos 60°, sin 60°).
    EXPECT_NEAR(a[0].x, 0.0, 1e-15);
    EXPECT_NEAR(a[0].y, -0.5, 1e-15);
    EXPECT_NEAR(a[0].z, std::sqrt(3.0) / 2.0, 1e-15);
    EXPECT_NEAR(a[0].elevation, 60.0, 1e-12);
    EXPECT_EQ(a[0].time, "2024-06-21T12:00");
    EXPECT_EQ(a[0].dni, 800.0);
    EXPECT_EQ(a[0].dhi, 100.0);
    EXPECT_EQ(a[1].line, 5u);
    const auto b = parse_sun_series(
        "time,sun_x,sun_y,sun_z,direct_normal_irradiance,diffuse_horizontal_irradiance\nt0,0,3,4,1,2\n", "v.csv");
    ASSERT_EQ(b.size(), 1u);
    EXPECT_NEAR(b[0].y, 0.6, 1e-15);
    EXPECT_NEAR(b[0].z, 0.8, 1e-15);
}

TEST(SunSeries, RefusesEveryBadLineNamingFileLineAndRule) {
    const std::string h = "time,azimuth,elevation,direct_normal_irradiance,diffuse_horizontal_irradiance\n";
    const std::string v = "time,sun_x,sun_y,sun_z,direct_normal_irradiance,diffuse_horizontal_irradiance\n";
    const std::vector<std::pair<std::string, std::string>> cases = {
        {"", "s.csv: empty"},
        {h, "s.csv: no steps"},
        {"time,az,el,dni,dhi\n1,2,3,4,5\n", "s.csv:1: the first line must be the header"},
        {h + "t,180,30,800\n", "s.csv:2: 4 fields"},
        {h + "t,180,thirty,800,100\n", "s.csv:2: elevation 'thirty' is not a finite number"},
        {h + "t,180,91,800,100\n", "s.csv:2: elevation 91 must be in [-90, 90]"},
        {h + "t,180,30,-1,100\n", "s.csv:2: direct_normal_irradiance -1 must be in [0, 100000] W/m^2"},
        {h + "t,180,30,800,-2\n", "s.csv:2: diffuse_horizontal_irradiance -2 must be in [0, 100000] W/m^2"},
        {h + "t,180,30,1e300,2\n", "s.csv:2: direct_normal_irradiance 1e+300 must be in [0, 100000] W/m^2"},
        {h + "t,180,30,inf,100\n", "s.csv:2: direct_normal_irradiance 'inf' is not a finite number"},
        {h + "t,180,30,800,\n", "s.csv:2: diffuse_horizontal_irradiance is missing"},
        {h + ",180,30,800,100\n", "s.csv:2: the time is empty"},
        {h + "t,180,30,800,100\n\nt,180,30,800,100\n", "s.csv:4: time 't' is listed again (first on line 2)"},
        {v + "t,0,0,0,800,100\n", "s.csv:2: the direction towards the sun must not be zero"},
        {h + "\"t,180,30,800,100\n", "s.csv:2: a double quote is not closed"},
    };
    for (const auto& [text, want] : cases) {
        const std::string got = message_of([&] { parse_sun_series(text, "s.csv"); });
        EXPECT_NE(got.find(want), std::string::npos) << "want '" << want << "', got '" << got << "'";
    }
}

TEST(Albedo, ReadsEveryObjectAndRefusesUnknownRepeatedMissingAndOutOfRange) {
    const std::vector<std::string> objects = {"ground", "roof", "wall, south"};
    const auto a = parse_albedo_csv("object,albedo\nroof,0.5\n\"wall, south\",0\nground,0.99\n", "a.csv", objects);
    EXPECT_EQ(a, (std::vector<double>{0.99, 0.5, 0.0}));
    const std::string h = "object,albedo\n";
    const std::vector<std::pair<std::string, std::string>> cases = {
        {"", "a.csv: empty"},
        {"name,albedo\n", "a.csv:1: the first line must be the header 'object,albedo'"},
        {h + "tree,0.2\n", "a.csv:2: the scene has no object 'tree'"},
        {h + "roof,0.2\nroof,0.3\n", "a.csv:3: object 'roof' is listed again (first on line 2)"},
        {h + "roof,1\n", "a.csv:2: albedo 1 of 'roof' must be in [0, 1)"},
        {h + "roof,-0.5\n", "a.csv:2: albedo -0.5 of 'roof' must be in [0, 1)"},
        {h + "roof,x\n", "a.csv:2: albedo 'x' is not a finite number"},
        {h + "roof\n", "a.csv:2: 1 fields"},
        {h + "roof,0.2\nground,0.1\n", "a.csv: 1 of the scene's 3 objects have no albedo, e.g. 'wall, south'"},
    };
    for (const auto& [text, want] : cases) {
        const std::string got = message_of([&] { parse_albedo_csv(text, "a.csv", objects); });
        EXPECT_NE(got.find(want), std::string::npos) << "want '" << want << "', got '" << got << "'";
    }
}

}  // namespace
}  // namespace ffcube

namespace ffcube {
namespace {

// Mangled files (bytes changed, cut, doubled): each is read or refused with an InputError, and
// what is read is sane (finite, a unit direction, irradiances in range, albedos in [0, 1)).
TEST(SunSeries, MangledFilesAreReadSanelyOrRefused) {
    const std::string series =
        "time,azimuth,elevation,direct_normal_irradiance,diffuse_horizontal_irradiance\n"
        "\"2024-06-21 06:00\",90,5.5,120.5,30\n07:00,100,15,400,60\n# note\n08:00,110,25.25,600,80\n";
    const std::string albedo = "object,albedo\nroof,0.2\n\"wall, south\",0.35\nground,0.1\n";
    const std::vector<std::string> objects = {"ground", "roof", "wall, south"};
    std::mt19937 rng(2024);
    const std::string alphabet = "0123456789.,-+e\"\n\r #xinfa";
    std::size_t read = 0, refused = 0;
    for (int trial = 0; trial < 4000; ++trial) {
        const bool is_series = trial % 2 == 0;
        std::string text = is_series ? series : albedo;
        const int edits = 1 + static_cast<int>(rng() % 3);
        for (int e = 0; e < edits; ++e) {
            const std::size_t at = rng() % (text.size() + 1);
            switch (rng() % 3) {
                case 0: if (at < text.size()) text[at] = alphabet[rng() % alphabet.size()]; break;
                case 1: text.insert(at, 1, alphabet[rng() % alphabet.size()]); break;
                default: text.erase(at, std::min<std::size_t>(rng() % 4, text.size() - std::min(at, text.size())));
            }
        }
        try {
            if (is_series) {
                for (const SunStep& s : parse_sun_series(text, "m.csv")) {
                    EXPECT_NEAR(s.x * s.x + s.y * s.y + s.z * s.z, 1.0, 1e-12) << text;
                    EXPECT_TRUE(s.dni >= 0.0 && s.dni <= 1e5 && s.dhi >= 0.0 && s.dhi <= 1e5) << text;
                    EXPECT_TRUE(std::isfinite(s.elevation) && !s.time.empty()) << text;
                }
            } else {
                for (const double a : parse_albedo_csv(text, "m.csv", objects)) EXPECT_TRUE(a >= 0.0 && a < 1.0) << text;
            }
            ++read;
        } catch (const InputError& e) {
            EXPECT_EQ(std::string(e.what()).rfind("m.csv", 0), 0u) << e.what();  // names the file first
            ++refused;
        }
    }
    EXPECT_GT(read, 100u);
    EXPECT_GT(refused, 100u);
}

}  // namespace
}  // namespace ffcube
