// View factors to the patches of a subdivided sky (raycast/sky_patches.hpp).
//
// The cosine integral. With d(alt, az) = (sin az cos alt, cos az cos alt, sin alt) and
// dω = cos alt d(alt) d(az), the vector M = ∫ d dω over the cell [a0, a1] × [φ0, φ1] is
//     M_x = C (cos φ0 − cos φ1),  M_y = C (sin φ1 − sin φ0),  M_z = Δφ (sin² a1 − sin² a0) / 2,
// C = ∫ cos² a da = (a1 − a0)/2 + (sin 2a1 − sin 2a0)/4. For a cell wholly in front of the patch
// (n·d ≥ 0 throughout) ∫ n·d dω = n·M exactly. A cell that the patch's plane crosses is halved
// in both directions up to horizon_depth times; a leaf still crossed counts max(n·M, 0), an error
// below the leaf's solid angle over π (a cell of 6°/16 is 1.4e-4 sr). Which cells the plane
// crosses is decided by n·d at the four corners and the centre (a great circle can clip a corner
// of a cell between those samples only by less than the cell's size).
//
// Visibility. From each sample point (the points (2/3, 1/6, 1/6) of the patch's triangles,
// weighted by the triangle's area) a ray along the leaf's mean direction M/|M| (nudged in front
// of the patch if needed), started a hair off the plane, skipping the patch itself; any surface
// met (front or back) blocks it. V_ip = Σ_leaves (n·M/π) × (open share of the sample points).
#include "ffcube/raycast/sky_patches.hpp"

#include <glm/geometric.hpp>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <numbers>
#include <thread>

#include "ffcube/core/error.hpp"
#include "ffcube/core/timer.hpp"
#include "ffcube/raycast/ray_scene.hpp"

namespace ffcube {
namespace {

constexpr double kPi = std::numbers::pi;

Vec3 direction(double alt, double az) { return {std::sin(az) * std::cos(alt), std::cos(az) * std::cos(alt), std::sin(alt)}; }

Vec3 cell_moment(double a0, double a1, double f0, double f1) {
    const double c = (a1 - a0) / 2.0 + (std::sin(2.0 * a1) - std::sin(2.0 * a0)) / 4.0;
    const double s1 = std::sin(a1), s0 = std::sin(a0);
    return {c * (std::cos(f0) - std::cos(f1)), c * (std::sin(f1) - std::sin(f0)), (f1 - f0) * (s1 * s1 - s0 * s0) / 2.0};
}

struct Leaf {
    Vec3 dir;
    double weight;  // ∫ n·d dω / π over the leaf (≥ 0)
};

void leaves(const Vec3& n, double a0, double a1, double f0, double f1, std::uint32_t depth, std::vector<Leaf>& out) {
    const double am = 0.5 * (a0 + a1), fm = 0.5 * (f0 + f1);
    int front = 0, back = 0;
    for (const auto& [a, f] : {std::pair{a0, f0}, {a0, f1}, {a1, f0}, {a1, f1}, {am, fm}}) {
        const double c = glm::dot(n, direction(a, f));
        front += c > 0.0;
        back += c < 0.0;
    }
    if (front == 0) return;  // wholly behind (or in) the patch's plane
    if (back > 0 && depth > 0) {
        leaves(n, a0, am, f0, fm, depth - 1, out);
        leaves(n, a0, am, fm, f1, depth - 1, out);
        leaves(n, am, a1, f0, fm, depth - 1, out);
        leaves(n, am, a1, fm, f1, depth - 1, out);
        return;
    }
    const Vec3 m = cell_moment(a0, a1, f0, f1);
    const double w = glm::dot(n, m) / kPi;
    if (!(w > 0.0)) return;
    Vec3 d = m / std::sqrt(glm::dot(m, m));
    const double c = glm::dot(n, d);
    if (c < 1e-6) d = glm::normalize(d + n * (1e-6 - c));
    out.push_back({d, w});
}

}  // namespace

std::vector<SkyPatch> tregenza_patches() {
    static constexpr int kCounts[8] = {30, 30, 24, 24, 18, 12, 6, 1};
    const double band = 12.0 * kPi / 180.0;
    std::vector<SkyPatch> out;
    for (int b = 0; b < 8; ++b) {
        const double a0 = b * band, a1 = b < 7 ? (b + 1) * band : kPi / 2.0;
        const double width = 2.0 * kPi / kCounts[b];
        for (int k = 0; k < kCounts[b]; ++k) {
            // Centred on north: the first patch spans [−w/2, w/2]; ranges kept increasing.
            const double c = k * width;
            out.push_back({a0, a1, c - width / 2.0, c + width / 2.0});
        }
    }
    return out;
}

SkyPatchViewFactors sky_patch_view_factors(const Scene& scene, const std::vector<SkyPatch>& sky, const SkyPatchOptions& o) {
    Stopwatch watch;
    if (o.cells < 1) throw InputError("sky patches: cells must be at least 1");
    SkyPatchViewFactors r;
    r.patches = static_cast<std::uint32_t>(scene.size());
    r.sky = static_cast<std::uint32_t>(sky.size());
    r.v.assign(std::size_t(r.patches) * r.sky, 0.0);
    if (scene.size() == 0) return r;
    const Scene& drawn = scene.drawn_scene();
    const RayScene rays(drawn);
    const Vec3 extent = drawn.bbox_max - drawn.bbox_min;
    const double lift = 1e-7 * std::max(1.0, std::sqrt(glm::dot(extent, extent)));
    const unsigned threads = o.threads > 0 ? o.threads : std::max(1u, std::thread::hardware_concurrency());
    std::atomic<std::uint32_t> next{0};
    std::vector<std::uint64_t> traced(threads, 0);
    const auto work = [&](unsigned t) {
        std::vector<Leaf> cells;
        std::vector<Vec3> points;
        std::vector<double> point_weight;
        for (std::uint32_t i = next++; i < r.patches; i = next++) {
            const Patch& p = scene.patches[i];
            points.clear();
            point_weight.clear();
            for (std::uint32_t tri = 0; tri + 2 < p.count; ++tri) {
                const Vec3 a = scene.positions[p.v[0]], b = scene.positions[p.v[tri + 1]], c = scene.positions[p.v[tri + 2]];
                const double area = 0.5 * std::sqrt(glm::dot(glm::cross(b - a, c - a), glm::cross(b - a, c - a)));
                for (const auto& [wa, wb, wc] : {std::tuple{4.0, 1.0, 1.0}, {1.0, 4.0, 1.0}, {1.0, 1.0, 4.0}}) {
                    points.push_back((a * wa + b * wb + c * wc) / 6.0 + p.normal * lift);
                    point_weight.push_back(area);
                }
            }
            double total_weight = 0.0;
            for (const double w : point_weight) total_weight += w;
            if (!(total_weight > 0.0)) continue;
            for (std::uint32_t q = 0; q < r.sky; ++q) {
                const SkyPatch& s = sky[q];
                cells.clear();
                const double da = (s.alt1 - s.alt0) / o.cells, df = (s.az1 - s.az0) / o.cells;
                for (std::uint32_t ka = 0; ka < o.cells; ++ka)
                    for (std::uint32_t kf = 0; kf < o.cells; ++kf)
                        leaves(p.normal, s.alt0 + ka * da, s.alt0 + (ka + 1) * da, s.az0 + kf * df, s.az0 + (kf + 1) * df,
                               o.horizon_depth, cells);
                double v = 0.0;
                for (const Leaf& leaf : cells) {
                    double open = 0.0;
                    for (std::size_t k = 0; k < points.size(); ++k)
                        if (rays.first_hit(points[k], leaf.dir, i).patch == RayScene::kNone) open += point_weight[k];
                    traced[t] += points.size();
                    v += leaf.weight * (open / total_weight);
                }
                r.v[std::size_t(i) * r.sky + q] = v;
            }
        }
    };
    std::vector<std::thread> pool;
    for (unsigned t = 1; t < threads; ++t) pool.emplace_back(work, t);
    work(0);
    for (std::thread& th : pool) th.join();
    for (const std::uint64_t x : traced) r.rays += x;
    r.seconds = watch.seconds();
    return r;
}

}  // namespace ffcube
