// Hand-made scenes and rows for the solver tests: no OBJ loading, no GL. Rows are held in double
// so that every method sees exactly the same values (a CsrMatrix would round them to float).
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <numbers>
#include <span>
#include <string>
#include <utility>
#include <vector>

#include "ffcube/formfactor/row_provider.hpp"
#include "ffcube/scene/scene.hpp"

namespace ffcube::test {

// A scene of patches with the given areas; patch i uses material material_of[i]. One object
// "all" unless object_of is given. Geometry (vertices, normals) is irrelevant to the solver.
inline Scene make_scene(const std::vector<double>& areas, const std::vector<Material>& materials,
                        const std::vector<std::uint32_t>& material_of, const std::vector<std::string>& objects = {"all"},
                        const std::vector<std::uint32_t>& object_of = {}) {
    Scene s;
    s.source = "test-scene";
    s.objects = objects;
    s.materials = materials;
    for (std::size_t i = 0; i < areas.size(); ++i) {
        Patch p;
        p.area = areas[i];
        p.material = material_of[i];
        p.object = object_of.empty() ? 0 : object_of[i];
        s.patches.push_back(p);
    }
    return s;
}

inline Material grey(const std::string& name, double rho, double emit) {
    return Material{name, Vec3(rho), Vec3(emit)};
}

// Rows in double, handed out on request; counts what was asked.
class ExactRowProvider final : public RowProvider {
public:
    explicit ExactRowProvider(std::vector<SparseRow> rows) : rows_(std::move(rows)), requests_(rows_.size(), 0) {}
    std::uint32_t size() const override { return static_cast<std::uint32_t>(rows_.size()); }
    std::string name() const override { return "exact"; }
    void compute_rows(std::span<const std::uint32_t> list, const RowSink& sink) override {
        ++calls_;
        for (std::uint32_t i : list) {
            ++requests_[i];
            sink(i, rows_[i]);
        }
    }
    std::uint64_t calls() const { return calls_; }
    std::uint64_t requests(std::uint32_t i) const { return requests_[i]; }
    std::uint64_t total_requests() const {
        std::uint64_t t = 0;
        for (auto r : requests_) t += r;
        return t;
    }
    const std::vector<SparseRow>& rows() const { return rows_; }

private:
    std::vector<SparseRow> rows_;
    std::vector<std::uint64_t> requests_;
    std::uint64_t calls_ = 0;
};

// Closed forms for a unit cube (Howell's catalogue, C-11 and C-14).
// Parallel, directly opposed unit squares one unit apart (X = Y = 1).
inline double cube_opposite_ff() {
    const double x = 1.0, y = 1.0;
    const double a = std::sqrt(1 + x * x), b = std::sqrt(1 + y * y);
    return 2.0 / (std::numbers::pi * x * y) *
           (std::log(std::sqrt((1 + x * x) * (1 + y * y) / (1 + x * x + y * y))) + x * b * std::atan(x / b) +
            y * a * std::atan(y / a) - x * std::atan(x) - y * std::atan(y));
}
// Perpendicular unit squares sharing an edge (W = H = 1).
inline double cube_adjacent_ff() {
    const double w = 1.0, h = 1.0, s = std::sqrt(h * h + w * w);
    const double t1 = (1 + w * w) * (1 + h * h) / (1 + w * w + h * h);
    const double t2 = std::pow(w * w * (1 + w * w + h * h) / ((1 + w * w) * (w * w + h * h)), w * w);
    const double t3 = std::pow(h * h * (1 + h * h + w * w) / ((1 + h * h) * (h * h + w * w)), h * h);
    return (w * std::atan(1 / w) + h * std::atan(1 / h) - s * std::atan(1 / s) + 0.25 * std::log(t1 * t2 * t3)) /
           (std::numbers::pi * w);
}

// The six faces of a unit cube; face 2k and 2k+1 are opposite. Each row sums to 1 up to rounding.
inline std::vector<SparseRow> cube_rows() {
    const double opp = cube_opposite_ff(), adj = cube_adjacent_ff();
    std::vector<SparseRow> rows(6);
    for (std::uint32_t i = 0; i < 6; ++i)
        for (std::uint32_t j = 0; j < 6; ++j) {
            if (j == i) continue;
            rows[i].col.push_back(j);
            rows[i].val.push_back((j ^ 1u) == i ? opp : adj);
        }
    return rows;
}

// A closed ring of n equal patches, each seeing only its two neighbours (F = 1/2 each): the
// slowest-mixing closed enclosure there is, so the stiffest at a given ρ.
inline std::vector<SparseRow> ring_rows(std::uint32_t n) {
    std::vector<SparseRow> rows(n);
    for (std::uint32_t i = 0; i < n; ++i) {
        std::uint32_t a = (i + n - 1) % n, b = (i + 1) % n;
        if (a > b) std::swap(a, b);
        rows[i].col = {a, b};
        rows[i].val = {0.5, 0.5};
    }
    return rows;
}

// Deterministic pseudo-random numbers in [0, 1) (splitmix64), the same on every platform.
inline double unit_random(std::uint64_t k) {
    std::uint64_t z = k + 0x9e3779b97f4a7c15ull;
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ull;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebull;
    z ^= z >> 31;
    return double(z >> 11) * 0x1.0p-53;
}

// An open, reciprocal scene of n patches: areas in [1, 3), symmetric couplings G_ij = A_i F_ij
// (about half of the pairs, plus a self term on patch 0 as a concave patch would have), scaled so
// that the largest row sum is max_row_sum. Reciprocity holds to rounding (F_ij = G_ij / A_i).
struct RandomScene {
    std::vector<double> areas;
    std::vector<SparseRow> rows;
};
inline RandomScene random_reciprocal(std::uint32_t n, double max_row_sum, std::uint64_t seed) {
    RandomScene r;
    for (std::uint32_t i = 0; i < n; ++i) r.areas.push_back(1.0 + 2.0 * unit_random(seed * 1000 + i));
    std::vector<double> g(std::size_t(n) * n, 0.0);
    for (std::uint32_t i = 0; i < n; ++i)
        for (std::uint32_t j = i + 1; j < n; ++j) {
            const double u = unit_random(seed * 100000 + i * n + j + 7777);
            if (u < 0.5) g[i * n + j] = g[j * n + i] = u;
        }
    g[0] = 0.3;
    double worst = 0.0;
    for (std::uint32_t i = 0; i < n; ++i) {
        double s = 0.0;
        for (std::uint32_t j = 0; j < n; ++j) s += g[i * n + j] / r.areas[i];
        worst = std::max(worst, s);
    }
    const double scale = max_row_sum / worst;
    r.rows.resize(n);
    for (std::uint32_t i = 0; i < n; ++i)
        for (std::uint32_t j = 0; j < n; ++j)
            if (g[i * n + j] > 0.0) {
                r.rows[i].col.push_back(j);
                r.rows[i].val.push_back(g[i * n + j] * scale / r.areas[i]);
            }
    return r;
}

inline double max_abs(std::span<const Vec3> b) {
    double m = 0.0;
    for (const Vec3& v : b) m = std::max({m, std::abs(v.x), std::abs(v.y), std::abs(v.z)});
    return m;
}
inline double max_abs_diff(std::span<const Vec3> a, std::span<const Vec3> b) {
    double m = 0.0;
    for (std::size_t i = 0; i < a.size(); ++i) {
        const Vec3 d = a[i] - b[i];
        m = std::max({m, std::abs(d.x), std::abs(d.y), std::abs(d.z)});
    }
    return m;
}

}  // namespace ffcube::test
