// ffcube radiate on tessellated two-surface enclosures: concentric spheres (icosahedra subdivided
// and pushed onto the spheres) and concentric closed cylinders (regular prisms with caps), F by
// ffcube's default rows (--method auto: rays, for these few large facets).
// Against σ(T1⁴ − T2⁴)/(1/ε1 + (A1/A2)(1/ε2 − 1)):
//  - with the tessellated areas, within a bound derived from F's measured accuracy (row sums, the
//    energy balance) and the measured spread of the outer radiosity (the formula's assumption);
//  - with the smooth bodies' areas, within that bound plus the meshing's error: the same formula
//    at the tessellated area ratio minus at the smooth one (the only place the shape enters).
#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <filesystem>
#include <iostream>
#include <map>
#include <nlohmann/json.hpp>
#include <sstream>

#include "cli/cli_util.hpp"

namespace ffcube::test {
namespace {

constexpr double kSigma = 5.670374419e-8;
constexpr double kPi = 3.14159265358979323846;
using V3 = std::array<double, 3>;

// An OBJ object from triangles or polygons (vertex lists), reversed when `inward`.
struct Mesh {
    std::vector<V3> v;
    std::vector<std::vector<int>> f;  // 0-based, counter-clockwise seen from outside
};

std::string obj_object(const std::string& name, const Mesh& m, bool inward, int& base) {
    std::ostringstream s;
    s.precision(17);
    s << "o " << name << "\n";
    for (const V3& p : m.v) s << "v " << p[0] << ' ' << p[1] << ' ' << p[2] << "\n";
    for (std::vector<int> f : m.f) {
        if (inward) std::reverse(f.begin(), f.end());
        s << "f";
        for (const int k : f) s << ' ' << base + k;
        s << "\n";
    }
    base += static_cast<int>(m.v.size());
    return s.str();
}

V3 scaled(V3 p, double r) {
    const double l = std::sqrt(p[0] * p[0] + p[1] * p[1] + p[2] * p[2]);
    return {p[0] * r / l, p[1] * r / l, p[2] * r / l};
}

// An icosahedron subdivided `levels` times (each triangle into 4), vertices on the sphere of radius r.
Mesh icosphere(double r, int levels) {
    const double t = (1.0 + std::sqrt(5.0)) / 2.0;
    Mesh m;
    for (const V3& p : std::vector<V3>{{-1, t, 0}, {1, t, 0}, {-1, -t, 0}, {1, -t, 0}, {0, -1, t}, {0, 1, t},
                                       {0, -1, -t}, {0, 1, -t}, {t, 0, -1}, {t, 0, 1}, {-t, 0, -1}, {-t, 0, 1}})
        m.v.push_back(scaled(p, r));
    m.f = {{0, 11, 5}, {0, 5, 1}, {0, 1, 7},  {0, 7, 10}, {0, 10, 11}, {1, 5, 9}, {5, 11, 4}, {11, 10, 2}, {10, 7, 6}, {7, 1, 8},
           {3, 9, 4},  {3, 4, 2}, {3, 2, 6},  {3, 6, 8},  {3, 8, 9},   {4, 9, 5}, {2, 4, 11}, {6, 2, 10}, {8, 6, 7},  {9, 8, 1}};
    for (int l = 0; l < levels; ++l) {
        std::map<std::pair<int, int>, int> mid;
        const auto midpoint = [&](int a, int b) {
            const auto key = std::minmax(a, b);
            if (const auto it = mid.find(key); it != mid.end()) return it->second;
            const V3 p{(m.v[a][0] + m.v[b][0]) / 2, (m.v[a][1] + m.v[b][1]) / 2, (m.v[a][2] + m.v[b][2]) / 2};
            m.v.push_back(scaled(p, r));
            return mid[key] = static_cast<int>(m.v.size()) - 1;
        };
        std::vector<std::vector<int>> faces;
        for (const auto& f : m.f) {
            const int a = midpoint(f[0], f[1]), b = midpoint(f[1], f[2]), c = midpoint(f[2], f[0]);
            faces.insert(faces.end(), {{f[0], a, c}, {f[1], b, a}, {f[2], c, b}, {a, b, c}});
        }
        m.f = std::move(faces);
    }
    return m;
}

// A closed regular k-gon prism of circumradius r from z = -h/2 to h/2, caps included.
Mesh prism(double r, double h, int k) {
    Mesh m;
    for (int i = 0; i < k; ++i) {
        const double a = 2.0 * kPi * i / k;
        m.v.push_back({r * std::cos(a), r * std::sin(a), -h / 2});
        m.v.push_back({r * std::cos(a), r * std::sin(a), h / 2});
    }
    std::vector<int> top, bottom;
    for (int i = 0; i < k; ++i) {
        const int j = (i + 1) % k;
        m.f.push_back({2 * i, 2 * j, 2 * j + 1, 2 * i + 1});
        top.push_back(2 * i + 1);
        bottom.push_back(2 * (k - 1 - i));
    }
    m.f.push_back(top);
    m.f.push_back(bottom);
    return m;
}

double polygon_area(const Mesh& m) {
    double a = 0.0;
    for (const auto& f : m.f) {
        V3 n{0, 0, 0};
        for (std::size_t k = 0; k < f.size(); ++k) {
            const V3 &p = m.v[f[k]], &q = m.v[f[(k + 1) % f.size()]];
            n[0] += p[1] * q[2] - p[2] * q[1];
            n[1] += p[2] * q[0] - p[0] * q[2];
            n[2] += p[0] * q[1] - p[1] * q[0];
        }
        a += 0.5 * std::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
    }
    return a;
}

// Σ of CSV column `name` over lines whose column `key` is `value` (first line is the header); or
// min/max of it.
struct ColumnStats {
    double sum = 0.0, min = 1e300, max = -1e300;
};
ColumnStats column_stats(const std::string& text, const std::string& key, const std::string& value, const std::string& name) {
    std::istringstream in(text);
    std::string line;
    std::getline(in, line);
    std::vector<std::string> header;
    for (std::stringstream h(line); std::getline(h, line, ',');) header.push_back(line);
    const auto col = [&](const std::string& c) { return std::find(header.begin(), header.end(), c) - header.begin(); };
    const std::size_t k = col(key), c = col(name);
    ColumnStats s;
    while (std::getline(in, line)) {
        std::vector<std::string> f;
        for (std::stringstream l(line); std::getline(l, line, ',');) f.push_back(line);
        if (f[k] != value) continue;
        const double x = std::stod(f[c]);
        s.sum += x;
        s.min = std::min(s.min, x);
        s.max = std::max(s.max, x);
    }
    return s;
}

double formula(double t1, double t2, double e1, double e2, double ratio) {
    return kSigma * (std::pow(t1, 4) - std::pow(t2, 4)) / (1.0 / e1 + ratio * (1.0 / e2 - 1.0));
}

// Runs the enclosure (inner, outer) with F computed once, for ε2 = 1 and 0.5, and checks q1.
void check_enclosure(const TempDir& dir, const std::string& scene_options, const Mesh& inner, const Mesh& outer,
                     double smooth_ratio, const std::string& label) {
    int base = 1;
    std::string text = obj_object("inner", inner, false, base);  // first: vertices from 1
    text += obj_object("outer", outer, true, base);
    write_file(dir / "e.obj", text);
    const std::string scene = (dir / "e.obj") + " " + scene_options;
    const RunResult ff = run_ffcube("formfactors " + scene + " -q -o " + (dir / "F.ffm") + " --report " + (dir / "ff.json"));
    ASSERT_EQ(ff.code, 0) << ff.output;
    const double a1 = polygon_area(inner), a2 = polygon_area(outer);
    const double t1 = 800.0, t2 = 300.0, e1 = 0.4;
    for (const double e2 : {1.0, 0.5}) {
        SCOPED_TRACE(testing::Message() << label << ", eps2 " << e2);
        write_file(dir / "s.csv", "object,emissivity,temperature,heat_flux\ninner," + std::to_string(e1) + "," +
                                      std::to_string(t1) + ",\nouter," + std::to_string(e2) + "," + std::to_string(t2) + ",\n");
        const RunResult r = run_ffcube("radiate " + scene + " -q --matrix " + (dir / "F.ffm") + " --surfaces " +
                                       (dir / "s.csv") + " --patch-out " + (dir / "p.csv") + " --report " + (dir / "r.json"));
        ASSERT_EQ(r.code, 0) << r.output;
        const auto report = nlohmann::json::parse(read_text(dir / "r.json"));
        const double delta = std::max(1.0 - double(report["row_sums"]["min"]), double(report["row_sums"]["max"]) - 1.0);
        const std::string p = read_text(dir / "p.csv");
        const ColumnStats j2 = column_stats(p, "object", "outer", "radiosity");
        // Power of the inner body from the patches (area × flux summed), per its tessellated area.
        double p1 = 0.0;
        {
            std::istringstream in(p);
            std::string line;
            std::getline(in, line);
            while (std::getline(in, line)) {
                std::vector<std::string> f;
                for (std::stringstream l(line); std::getline(l, line, ',');) f.push_back(line);
                if (f[1] == "inner") p1 += std::stod(f[2]) * std::stod(f[4]);
            }
        }
        const double q1 = p1 / a1;
        const double closed = formula(t1, t2, e1, e2, a1 / a2);
        // The bound (derived in test_radiate_cli.cpp, InnerCubeInClosedBox): the inner body is convex,
        // so its mean irradiation lies in [s_min J2min, s_max J2max]; the closed form assumes a uniform
        // J2*, which differs from the mean by ((1 − ε2)/ε2)(A1 (q1* − q1) ± e)/A2, e the balance error:
        //   |q1 − q1*| ≤ ε1 [ (J2max − J2min) + δ J2max + k e/A2 ] / (1 − ε1 k A1/A2),  k = (1 − ε2)/ε2,
        // plus the CSV's 10 digits on every patch's area and flux (1e-9 relative).
        const double e = double(report["energy"]["relative_error"]) * double(report["energy"]["absolute_power"]);
        const double k = (1.0 - e2) / e2;
        const double bound = e1 * ((j2.max - j2.min) + delta * j2.max + k * e / a2) / (1.0 - e1 * k * a1 / a2) + 1e-8 * closed;
        EXPECT_NEAR(q1, closed, bound) << "row sums within " << delta << ", J2 " << j2.min << ".." << j2.max;
        // The smooth bodies: the meshing moves the formula by |f(A1/A2) − f(smooth ratio)|.
        const double smooth = formula(t1, t2, e1, e2, smooth_ratio);
        const double meshing = std::abs(closed - smooth);
        EXPECT_NEAR(q1, smooth, bound + meshing);
        std::cout << "[measured] " << label << " eps2 " << e2 << ": q1 " << q1 << " W/m2; tessellated closed form "
                  << closed << " (rel error " << std::abs(q1 - closed) / closed << ", bound " << bound / closed
                  << "); smooth " << smooth << " (rel error " << std::abs(q1 - smooth) / smooth << ", meshing part "
                  << meshing / smooth << ")\n";
    }
}

TEST(RadiateEnclosures, ConcentricSpheres) {
    TempDir dir;
    // r1 = 0.5 (an icosahedron, 20 triangles), r2 = 1 (80 triangles): smooth A1/A2 = (r1/r2)² = 1/4,
    // tessellated 2.394/11.666 = 0.205 (the inner is coarser).
    check_enclosure(dir, "--no-subdivide", icosphere(0.5, 0), icosphere(1.0, 1), 0.25, "spheres");
}

TEST(RadiateEnclosures, ConcentricClosedCylinders) {
    TempDir dir;
    // Inner r1 = 0.4, h1 = 1 (16-gon); outer r2 = 1, h2 = 2 (24-gon), caps included: smooth areas
    // 2πr h + 2πr².
    const double r1 = 0.4, h1 = 1.0, r2 = 1.0, h2 = 2.0;
    const double smooth = (2 * kPi * r1 * h1 + 2 * kPi * r1 * r1) / (2 * kPi * r2 * h2 + 2 * kPi * r2 * r2);
    check_enclosure(dir, "--max-patch-edge 0.5", prism(r1, h1, 16), prism(r2, h2, 24), smooth, "cylinders");
}

}  // namespace
}  // namespace ffcube::test
