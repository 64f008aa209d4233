#include "ffcube/raycast/raycast_provider.hpp"

#include <embree3/rtcore.h>
#include <glm/common.hpp>
#include <glm/geometric.hpp>
#include <glm/vec2.hpp>
#include <fmt/format.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <limits>
#include <mutex>
#include <span>
#include <numbers>
#include <thread>
#include <vector>

#include "ffcube/core/error.hpp"
#include "ffcube/formfactor/ordered_pool.hpp"
#include "ffcube/geometry/polygon.hpp"
#include "ffcube/hemicube/pieces.hpp"
#include "raycast/embree_mesh.hpp"
#include "raycast/sampling.hpp"

namespace ffcube {
namespace {

using namespace raycast_sampling;

// splitmix64: a full-period 64-bit generator that passes BigCrush; seeded per row, so a row's
// scrambling seeds depend on (seed, row) only.
struct Rng {
    std::uint64_t s;
    std::uint64_t next() {
        std::uint64_t z = (s += 0x9e3779b97f4a7c15ull);
        z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ull;
        z = (z ^ (z >> 27)) * 0x94d049bb133111ebull;
        return z ^ (z >> 31);
    }
};

Rng row_rng(std::uint64_t seed, std::uint32_t row) {
    Rng r{seed ^ 0x6a09e667f3bcc909ull};
    r.s ^= r.next() + 0x9e3779b97f4a7c15ull * (static_cast<std::uint64_t>(row) + 1);
    r.next();
    return r;
}

// Up to 16 rays in flight: Embree's packet and, per lane, the ray's sample (u, v on the sender,
// r1, r2 on the direction square), origin, direction and weight in double.
struct Packet {
    RTCRayHit16 rh;  // RTC_ALIGN(64) members
    alignas(64) int valid[16];
    alignas(64) std::uint32_t word[4][16] = {};  // the sample's r1, r2, u, v as 32-bit fractions
    alignas(64) double u[16] = {}, v[16] = {}, r1[16] = {}, r2[16] = {};
    alignas(64) double ox[16], oy[16], oz[16], dx[16], dy[16], dz[16], w[16];
    int lanes = 0;
};

// What a row's rays need of their sender, in Embree's coordinates where marked.
struct Sender {
    Vec3 c[4]{};            // corners (scene coordinates; c[3] zero and unused for a triangle)
    int count = 3;
    bool parallelogram = true;
    Vec3 tu, tv, n;         // tangent frame, n the normal
    Vec3 center;            // Embree's centre and scale
    double scale = 1.0, offset = 0.0;  // origins sit offset in front (Embree units)
};

// Lanes [0, lanes) of pk from their (u, v, r1, r2): the point on the sender (area-uniform: on a
// triangle through √u, on a quad bilinear with weight |∂x/∂u × ∂x/∂v| unless a parallelogram)
// lifted offset along the normal, and the cosine-weighted direction (concentric_disk lifted to
// the hemisphere about the sender's frame). Loops over plain arrays, so the compiler vectorizes
// them (with this file's -fno-math-errno -fno-trapping-math, src/CMakeLists.txt); an AVX2 copy
// where the CPU has it (make_rays picks one at start-up: a plain check, not an ifunc, which
// sanitizers dislike).
// The same bits either way (checked: the same .ffm with either copy): IEEE +, ×, ÷ and √ round
// alike in any width, and neither copy contracts to FMA (no fma target).
__attribute__((always_inline)) inline void make_rays_body(Packet& pk, const Sender& s) {
    // All 16 lanes (a fixed trip count vectorizes; lanes past pk.lanes are left out by the
    // packet's valid mask), from locals that no store can alias.
    constexpr int L = 16;
    const double tux = s.tu.x, tuy = s.tu.y, tuz = s.tu.z, tvx = s.tv.x, tvy = s.tv.y, tvz = s.tv.z;
    const double nx = s.n.x, ny = s.n.y, nz = s.n.z;
    double* __restrict dx = pk.dx;
    double* __restrict dy = pk.dy;
    double* __restrict dz = pk.dz;
    // The words as doubles: cell midpoints of the 2^-32 grid, (w + 0.5) · 2^-32 exactly, through
    // a signed conversion (which vectorizes; every value is exact in a double either way).
    for (int d = 0; d < 4; ++d) {
        double* __restrict out = d == 0 ? pk.r1 : d == 1 ? pk.r2 : d == 2 ? pk.u : pk.v;
        const std::uint32_t* __restrict w = pk.word[d];
        for (int l = 0; l < L; ++l)
            out[l] = (static_cast<double>(static_cast<std::int32_t>(w[l] ^ 0x80000000u)) + 2147483648.5) * 0x1.0p-32;
    }
    const double* __restrict r1 = pk.r1;
    const double* __restrict r2 = pk.r2;
    for (int l = 0; l < L; ++l) {
        double x = 0.0, y = 0.0;
        concentric_disk(r1[l], r2[l], x, y);
        const double zz = 1.0 - x * x - y * y;
        const double z = std::sqrt(zz > 0.0 ? zz : 0.0);
        dx[l] = x * tux + y * tvx + z * nx;
        dy[l] = x * tuy + y * tvy + z * ny;
        dz[l] = x * tuz + y * tvz + z * nz;
    }
    const double* __restrict u = pk.u;
    const double* __restrict v = pk.v;
    double* __restrict w = pk.w;
    alignas(64) double px[L], py[L], pz[L];
    const double c0x = s.c[0].x, c0y = s.c[0].y, c0z = s.c[0].z, c1x = s.c[1].x, c1y = s.c[1].y, c1z = s.c[1].z;
    const double c2x = s.c[2].x, c2y = s.c[2].y, c2z = s.c[2].z, c3x = s.c[3].x, c3y = s.c[3].y, c3z = s.c[3].z;
    if (s.count == 3) {
        for (int l = 0; l < L; ++l) {
            const double su = std::sqrt(u[l]);
            const double a0 = 1.0 - su, a1 = su * (1.0 - v[l]), a2 = su * v[l];
            px[l] = a0 * c0x + a1 * c1x + a2 * c2x;
            py[l] = a0 * c0y + a1 * c1y + a2 * c2y;
            pz[l] = a0 * c0z + a1 * c1z + a2 * c2z;
            w[l] = 1.0;
        }
    } else {
        for (int l = 0; l < L; ++l) {
            const double a0 = (1 - u[l]) * (1 - v[l]), a1 = u[l] * (1 - v[l]), a2 = u[l] * v[l], a3 = (1 - u[l]) * v[l];
            px[l] = a0 * c0x + a1 * c1x + a2 * c2x + a3 * c3x;
            py[l] = a0 * c0y + a1 * c1y + a2 * c2y + a3 * c3y;
            pz[l] = a0 * c0z + a1 * c1z + a2 * c2z + a3 * c3z;
            w[l] = 1.0;
        }
        if (!s.parallelogram)
            for (int l = 0; l < pk.lanes; ++l) {
                const Vec3 du = (1 - v[l]) * (s.c[1] - s.c[0]) + v[l] * (s.c[2] - s.c[3]);
                const Vec3 dv = (1 - u[l]) * (s.c[3] - s.c[0]) + u[l] * (s.c[2] - s.c[1]);
                w[l] = glm::length(glm::cross(du, dv));
            }
    }
    const double cx = s.center.x, cy = s.center.y, cz = s.center.z, sc = s.scale;
    const double offx = s.offset * nx, offy = s.offset * ny, offz = s.offset * nz;
    double* __restrict ox = pk.ox;
    double* __restrict oy = pk.oy;
    double* __restrict oz = pk.oz;
    for (int l = 0; l < L; ++l) {
        ox[l] = (px[l] - cx) * sc + offx;
        oy[l] = (py[l] - cy) * sc + offy;
        oz[l] = (pz[l] - cz) * sc + offz;
    }
    float* __restrict fox = pk.rh.ray.org_x;
    float* __restrict foy = pk.rh.ray.org_y;
    float* __restrict foz = pk.rh.ray.org_z;
    float* __restrict fdx = pk.rh.ray.dir_x;
    float* __restrict fdy = pk.rh.ray.dir_y;
    float* __restrict fdz = pk.rh.ray.dir_z;
    for (int l = 0; l < L; ++l) {
        fox[l] = static_cast<float>(ox[l]), foy[l] = static_cast<float>(oy[l]), foz[l] = static_cast<float>(oz[l]);
        fdx[l] = static_cast<float>(dx[l]), fdy[l] = static_cast<float>(dy[l]), fdz[l] = static_cast<float>(dz[l]);
    }
}

#define FFCUBE_VECTORIZE optimize("tree-vectorize", "vect-cost-model=dynamic")
__attribute__((target("avx2"), FFCUBE_VECTORIZE)) void make_rays_avx2(Packet& pk, const Sender& s) {
    make_rays_body(pk, s);
}
__attribute__((FFCUBE_VECTORIZE)) void make_rays_plain(Packet& pk, const Sender& s) { make_rays_body(pk, s); }
void make_rays(Packet& pk, const Sender& s) {
    static const auto chosen = __builtin_cpu_supports("avx2") ? &make_rays_avx2 : &make_rays_plain;
    chosen(pk, s);
}

// scramble_body (sampling.hpp) the same way: an AVX2 copy where the CPU has it.
__attribute__((target("avx2"), FFCUBE_VECTORIZE)) void scramble_avx2(std::uint32_t* words, std::size_t n,
                                                                      const std::uint32_t seed[4]) {
    scramble_body(words, n, seed);
}
__attribute__((FFCUBE_VECTORIZE)) void scramble_plain(std::uint32_t* words, std::size_t n, const std::uint32_t seed[4]) {
    scramble_body(words, n, seed);
}
void scramble(std::uint32_t* words, std::size_t n, const std::uint32_t seed[4]) {
    static const auto chosen = __builtin_cpu_supports("avx2") ? &scramble_avx2 : &scramble_plain;
    chosen(words, n, seed);
}
#undef FFCUBE_VECTORIZE

// Whether point x lies in the convex polygon poly (its plane, normal n), edges included within a
// relative 1e-9 of the polygon's size.
bool in_convex_polygon(const Vec3& x, std::span<const Vec3> poly, const Vec3& n, double size) {
    for (std::size_t k = 0; k < poly.size(); ++k) {
        const Vec3& a = poly[k];
        const Vec3& b = poly[(k + 1) % poly.size()];
        if (glm::dot(glm::cross(b - a, x - a), n) < -1e-9 * size * size) return false;
    }
    return true;
}

// Per patch, its twin: the patch of the other face of a two-sided plate (two one-sided pieces
// with the same corners, facing opposite ways: hemicube/pieces.hpp's twin_pairs) that covers the
// same place, or kNoPatch. The hemicube never shows such a piece's back (its twin's front covers
// the same pixels); the ray caster does the same with a hit on the back of a patch that has a
// twin (Embree picks either of two coincident triangles). A patch's twin is the lowest-numbered
// patch of the twin piece that contains its centroid: the same patch where both sides are meshed
// alike, the nearest cover otherwise (docs/accuracy.md, "Coincident and touching geometry"). The
// twin piece's patches are put in buckets of a uniform grid over the piece (about one a bucket,
// each in the buckets its box meets), so a piece of any size pairs in linear time.
std::vector<std::uint32_t> twin_patches(const Scene& scene) {
    std::vector<std::uint32_t> twin(scene.size(), kNoPatch);
    const auto cells = [&](std::uint32_t g) {
        const std::uint32_t end =
            g + 1 < scene.grids.size() ? scene.grids[g + 1].first_patch : static_cast<std::uint32_t>(scene.patches.size());
        return std::pair{scene.grids[g].first_patch, end};
    };
    std::vector<std::vector<std::uint32_t>> bucket;
    // Each patch of piece a against the patches of piece b.
    const auto pair_up = [&](std::uint32_t a, std::uint32_t b) {
        const auto [a0, a1] = cells(a);
        const auto [b0, b1] = cells(b);
        const PatchGrid& gb = scene.grids[b];
        // b's plane coordinates: u along its first edge, v across it.
        const Vec3 o = gb.corners[0];
        const Vec3 u = glm::normalize(gb.corners[1] - gb.corners[0]);
        const Vec3 v = glm::normalize(glm::cross(polygon_normal(std::span<const Vec3>(gb.corners.data(), gb.count)), u));
        const auto at = [&](const Vec3& x) { return glm::dvec2(glm::dot(x - o, u), glm::dot(x - o, v)); };
        std::vector<std::pair<glm::dvec2, glm::dvec2>> box(b1 - b0);
        glm::dvec2 lo(INFINITY), hi(-INFINITY);
        for (std::uint32_t q = b0; q < b1; ++q) {
            const auto c = scene.patch_vertices(q);
            const double slack = 1e-6 * scene.patches[q].size;  // beyond in_convex_polygon's 1e-9
            glm::dvec2 qlo(INFINITY), qhi(-INFINITY);
            for (std::uint32_t k = 0; k < scene.patches[q].count; ++k) {
                const glm::dvec2 p = at(c[k]);
                qlo = glm::min(qlo, p - slack), qhi = glm::max(qhi, p + slack);
            }
            box[q - b0] = {qlo, qhi};
            lo = glm::min(lo, qlo), hi = glm::max(hi, qhi);
        }
        const int side = std::max(1, static_cast<int>(std::sqrt(static_cast<double>(b1 - b0))));
        const glm::dvec2 scale = static_cast<double>(side) / glm::max(hi - lo, glm::dvec2(1e-300));
        const auto cell = [&](double x, double lo_x, double s) {  // clamped before the cast
            return static_cast<int>(std::clamp(std::floor((x - lo_x) * s), 0.0, static_cast<double>(side - 1)));
        };
        bucket.assign(static_cast<std::size_t>(side) * side, {});
        for (std::uint32_t q = b0; q < b1; ++q) {  // ascending: a bucket lists its patches in order
            const auto& [qlo, qhi] = box[q - b0];
            for (int y = cell(qlo.y, lo.y, scale.y); y <= cell(qhi.y, lo.y, scale.y); ++y)
                for (int x = cell(qlo.x, lo.x, scale.x); x <= cell(qhi.x, lo.x, scale.x); ++x)
                    bucket[static_cast<std::size_t>(y) * side + x].push_back(q);
        }
        for (std::uint32_t p = a0; p < a1; ++p) {
            const Vec3& x = scene.patches[p].centroid;
            const glm::dvec2 xp = at(x);
            for (const std::uint32_t q : bucket[static_cast<std::size_t>(cell(xp.y, lo.y, scale.y)) * side +
                                                cell(xp.x, lo.x, scale.x)]) {
                const auto corners = scene.patch_vertices(q);
                const Patch& pq = scene.patches[q];
                if (in_convex_polygon(x, std::span<const Vec3>(corners.data(), pq.count), pq.normal, pq.size)) {
                    twin[p] = q;
                    break;
                }
            }
        }
    };
    for (const auto& [a, b] : twin_pairs(scene.grids)) {
        pair_up(a, b);
        pair_up(b, a);
    }
    return twin;
}

constexpr std::uint32_t kChunk = 65536;  // points made and sorted at a time (1 MiB of scratch)

// The top b bits of a 32-bit fraction: its cell in a grid of 2^b.
std::uint32_t top_bits(std::uint32_t x, int b) { return b == 0 ? 0u : x >> (32 - b); }

}  // namespace

struct RaycastRowProvider::Impl {
    const Scene& scene;
    RaycastOptions opt;
    unsigned threads = 1;
    EmbreeMesh mesh;                          // the scene in Embree coordinates
    std::vector<std::uint8_t> parallelogram;  // per patch: uniform bilinear sampling, weight 1
    std::vector<Vec3> normal;                 // per patch, packed: every hit reads one
    std::vector<std::uint32_t> twin;          // per patch: twin_patches (kNoPatch: none)
    // The statistics (RaycastStats), each row's merged under the lock once the row is done.
    mutable std::mutex stats_mutex;
    mutable RaycastStats totals;
    void add(const RaycastStats& s) const {
        const std::lock_guard lock(stats_mutex);
        stats::merge(totals, s);
    }
    // A row refined to the tolerance, and whether it stopped at the budget above it.
    void add_traced(std::uint64_t rays) const {
        RaycastStats s;
        s.rays_traced = rays;
        add(s);
    }
    void note(const RowFigures& f) const {
        RaycastStats s;
        s.refined_rows = 1;
        s.rows_at_budget = f.noise <= opt.tolerance ? 0 : 1;
        add(s);
    }

    Impl(const Scene& s, const RaycastOptions& o) : scene(s), opt(o) {
        if (opt.rays == 0) throw InputError("raycast: the number of rays per row must be at least 1");
        if (!(opt.tolerance >= 0) || !std::isfinite(opt.tolerance))
            throw InputError(fmt::format("raycast: tolerance {} must be a finite number >= 0", opt.tolerance));
        threads = opt.threads ? opt.threads : std::max(1u, std::thread::hardware_concurrency());
        if (scene.size() == 0) return;
        build_embree_mesh(scene, mesh, "raycast");
        parallelogram.resize(scene.size());
        normal.resize(scene.size());
        for (std::uint32_t i = 0; i < scene.size(); ++i) normal[i] = scene.patches[i].normal;
        twin = twin_patches(scene);
        for (std::uint32_t i = 0; i < scene.size(); ++i) {
            const Patch& p = scene.patches[i];
            if (p.count != 4) continue;
            const auto c = scene.patch_vertices(i);
            parallelogram[i] = glm::length(c[0] + c[2] - c[1] - c[3]) <= 1e-12 * p.size;
        }
    }

    static constexpr double kSameNormal = 1.0 - 1e-12;
    // Whether a hit on patch j, for a ray leaving patch i, is a float artefact to pass through:
    // a ray leaving i's front can hit neither i nor a patch in i's plane.
    // The normals from the packed array first: most hits need not read the patches.
    bool pass_through(std::uint32_t i, std::uint32_t j) const {
        if (i == j) return true;
        if (!(glm::dot(normal[i], normal[j]) > kSameNormal)) return false;
        const Patch& a = scene.patches[i];
        const Patch& b = scene.patches[j];
        return std::abs(glm::dot(b.centroid - a.centroid, a.normal)) <= 1e-9 * std::max(a.size, b.size);
    }

    // Accuracy by target (RaycastOptions::tolerance): the row as the mean of kReplicates
    // independently scrambled copies of the sequence (randomized quasi-Monte Carlo), whose spread
    // is the row's measured error. Each copy's first m points are a net for every power of two m,
    // so the copies double together, from tolerance_rays' least count, until the estimate
    // t · σ of the mean, for the largest entry and for the row's sum (entries `exact` will replace
    // left out of both), is at most the tolerance, or the budget is spent. Student's t for
    // kReplicates − 1 degrees of freedom makes it a 95% two-sided bound when the copies' errors
    // are about normal (docs/accuracy.md, "Accuracy by target"). `cast` is row()'s cast_points,
    // `wsum` the weight it adds to.
    template <class Cast>
    void replicated_row(Rng& rng, SparseRow& out, RowScratch& sc, double& wsum, Cast& cast,
                        std::span<const std::pair<std::uint32_t, double>> exact, RowFigures* figures) const {
        constexpr std::size_t K = kReplicates;
        std::uint32_t seeds[K][4], states[K][4] = {};
        for (auto& sd : seeds)
            for (std::uint32_t& w : sd) w = static_cast<std::uint32_t>(rng.next() >> 32);
        double weight[K] = {};
        if (sc.slot.size() != scene.size()) sc.slot.assign(scene.size(), kNoSlot);
        sc.cols.clear();
        sc.rep.clear();
        const auto [least, most] = tolerance_rays(opt.tolerance);
        std::uint64_t done = 0, target = least / K;  // points per copy
        double estimate = INFINITY;
        for (;;) {
            for (std::size_t k = 0; k < K; ++k) {
                wsum = 0.0;
                cast(done, target, states[k], seeds[k]);
                weight[k] += wsum;
                for (const std::uint32_t j : sc.touched) {
                    if (sc.slot[j] == kNoSlot) {
                        sc.slot[j] = static_cast<std::uint32_t>(sc.cols.size());
                        sc.cols.push_back(j);
                        sc.rep.resize(sc.rep.size() + K, 0.0);
                    }
                    sc.rep[sc.slot[j] * K + k] += sc.acc[j];
                    sc.acc[j] = 0.0;
                }
                sc.touched.clear();
            }
            done = target;
            // The spread of the copies: per entry, and of their sums over the entries kept.
            double sums[K] = {}, worst = 0.0;
            for (std::size_t c = 0; c < sc.cols.size(); ++c) {
                const std::uint32_t j = sc.cols[c];
                const auto at = std::lower_bound(exact.begin(), exact.end(), j,
                                                 [](const auto& e, std::uint32_t x) { return e.first < x; });
                if (at != exact.end() && at->first == j) continue;
                double v[K], mean = 0.0;
                for (std::size_t k = 0; k < K; ++k) mean += v[k] = sc.rep[c * K + k] / weight[k], sums[k] += v[k];
                mean /= K;
                double ss = 0.0;
                for (std::size_t k = 0; k < K; ++k) ss += (v[k] - mean) * (v[k] - mean);
                worst = std::max(worst, ss);
            }
            double mean = 0.0, ss = 0.0;
            for (std::size_t k = 0; k < K; ++k) mean += sums[k];
            mean /= K;
            for (std::size_t k = 0; k < K; ++k) ss += (sums[k] - mean) * (sums[k] - mean);
            // σ of a mean of K: √(ss / (K − 1) / K).
            // Below it, what no ray has seen yet (the rule of three: tolerance_rays).
            estimate = std::max(kReplicateT * std::sqrt(std::max(worst, ss) / static_cast<double>((K - 1) * K)),
                                3.0 / static_cast<double>(done * K));
            if (estimate <= opt.tolerance || 2 * done * K > most) break;
            target = 2 * done;
        }
        // The row: the copies' mean, columns in order.
        std::sort(sc.cols.begin(), sc.cols.end());
        for (const std::uint32_t j : sc.cols) {
            const std::uint32_t c = sc.slot[j];
            double v = 0.0;
            for (std::size_t k = 0; k < K; ++k) v += sc.rep[c * K + k] / weight[k];
            out.col.push_back(j);
            out.val.push_back(v / K);
        }
        for (const std::uint32_t j : sc.cols) sc.slot[j] = kNoSlot;
        if (figures) {
            figures->noise = estimate;
            figures->rays = done * K;
        }
    }

    // Row i into out; the scratch's acc (size n, all zero) and touched (empty) are left as they
    // were found.
    //
    // Sampling (sampling.hpp): the row's rays are the first R points of a 4-D Sobol' sequence,
    // Owen-scrambled with seeds drawn from (seed, row): (r1, r2) the direction, through the
    // cosine-weighted concentric map, (u, v) the origin on the patch. Every ray is uniform on its
    // own, so the row is unbiased for any R; the first 4^k rays put one direction in each cell of a
    // 2^k × 2^k grid and spread the origins as evenly, jointly with the directions. They are made
    // kChunk at a time and cast in the tile order of their direction cells (tile_key), traced 16
    // at a time (rtcIntersect16), their hits counted in that order.
    void row(std::uint32_t i, SparseRow& out, RowScratch& scratch, std::span<const std::pair<std::uint32_t, double>> exact = {},
             RowFigures* figures = nullptr) const {
        std::vector<double>& acc = scratch.acc;
        std::vector<std::uint32_t>& touched = scratch.touched;
        std::vector<std::uint32_t>& points = scratch.points;
        std::vector<std::uint32_t>& sorted = scratch.sorted;
        std::vector<std::uint32_t>& start = scratch.start;
        std::vector<std::uint32_t>& order = scratch.order;
        out.clear();
        const Patch& p = scene.patches[i];
        Sender snd;
        const auto c = scene.patch_vertices(i);
        for (std::size_t k = 0; k < c.size() && k < 4; ++k) snd.c[k] = c[k];
        snd.count = p.count;
        snd.parallelogram = p.count != 4 || parallelogram[i];
        orthonormal_basis(p.normal, snd.tu, snd.tv);
        snd.n = p.normal;
        snd.center = mesh.center;
        snd.scale = mesh.scale;
        snd.offset = std::max(kOriginOffset * p.size * mesh.scale, kMinOffset);
        Rng rng = row_rng(opt.seed, i);
        double wsum = 0.0;
        std::uint64_t traced_here = 0;
        RTCIntersectContext ctx;
        rtcInitIntersectContext(&ctx);
        ctx.flags = RTC_INTERSECT_CONTEXT_FLAG_COHERENT;
        Packet pk;
        for (int l = 0; l < 16; ++l) {
            pk.rh.ray.time[l] = 0.0f;
            pk.rh.ray.mask[l] = 0xFFFFFFFFu;
            pk.rh.ray.id[l] = 0;
            pk.rh.ray.flags[l] = 0;
        }
        const auto trace = [&]() {
            if (pk.lanes == 0) return;
            make_rays(pk, snd);
            for (int l = 0; l < 16; ++l) {
                pk.valid[l] = l < pk.lanes ? -1 : 0;
                pk.rh.ray.tnear[l] = 0.0f;
                pk.rh.ray.tfar[l] = std::numeric_limits<float>::infinity();
                pk.rh.hit.geomID[l] = RTC_INVALID_GEOMETRY_ID;
                pk.rh.hit.primID[l] = RTC_INVALID_GEOMETRY_ID;
            }
            rtcIntersect16(pk.valid, mesh.embree.scene, &ctx, &pk.rh);
            traced_here += static_cast<std::uint64_t>(pk.lanes);
            for (int l = 0; l < pk.lanes; ++l) {
                wsum += pk.w[l];
                if (pk.rh.hit.geomID[l] == RTC_INVALID_GEOMETRY_ID) continue;  // left the scene
                std::uint32_t j = mesh.tri_patch[pk.rh.hit.primID[l]];
                const Vec3 d(pk.dx[l], pk.dy[l], pk.dz[l]);
                // A hit on the ray's own patch (or its plane) can only be float rounding: trace
                // on past it, a few times at most (then the ray is dropped, as if absorbed).
                if (pass_through(i, j))
                    j = first_patch(mesh, ctx, Vec3(pk.ox[l], pk.oy[l], pk.oz[l]), d,
                                    [&](std::uint32_t q) { return pass_through(i, q); }, traced_here,
                                    std::nextafter(pk.rh.ray.tfar[l], std::numeric_limits<float>::infinity()),
                                    kRetraces - 1);
                // A front face receives; so does either side of an obstruction-only patch, whose
                // factor is measured only to be left out (Scene::drawn), so that it is not sky.
                // The back of one face of a two-sided plate is its twin's front.
                if (j == kNoPatch) continue;
                bool front = glm::dot(d, normal[j]) < 0.0;
                if (!front && twin[j] != kNoPatch) j = twin[j], front = true;
                if (front || j >= scene.obstruction_first) {
                    if (acc[j] == 0.0) touched.push_back(j);
                    acc[j] += pk.w[l];
                }
            }
            pk.lanes = 0;
        };
        // Points [first, first + count) of the sequence scrambled by `seed` (its Gray-code walk at
        // `state`) in chunks of at most kChunk (each an aligned block of the sequence, so a net of
        // its own), each chunk cast in its direction cells' tile order.
        const auto cast_points = [&](std::uint64_t first, std::uint64_t end, std::uint32_t state[4],
                                     const std::uint32_t seed[4]) {
            while (first < end) {
                const auto count = static_cast<std::uint32_t>(std::min<std::uint64_t>(kChunk, end - first));
                points.resize(4 * static_cast<std::size_t>(count));
                sobol_walk(first, count, state, points.data());
                scramble(points.data(), count, seed);
                // Counting sort by the direction cell of a 2^b × 2^b grid, 16 · 4^b ≤ count: about
                // one packet a cell (exactly 16 points each for a count of 4^k: the directions are a
                // (0,2)-net), the cells in tile order.
                int b = 0;
                while (b < 12 && (std::uint64_t{64} << (2 * b)) <= count) ++b;
                const std::uint32_t cells = 1u << (2 * b);
                start.assign(cells + 1, 0);
                order.resize(count);  // each point's cell, then the points sorted, one dimension after another
                for (std::uint32_t k = 0; k < count; ++k) {
                    const std::uint32_t* q = &points[4 * static_cast<std::size_t>(k)];
                    order[k] = tile_key(top_bits(q[0], b), top_bits(q[1], b), b);
                    ++start[order[k] + 1];
                }
                for (std::uint32_t cell = 0; cell < cells; ++cell) start[cell + 1] += start[cell];
                sorted.resize(4 * static_cast<std::size_t>(count));
                for (std::uint32_t k = 0; k < count; ++k)
                    std::copy_n(&points[4 * static_cast<std::size_t>(k)], 4,
                                &sorted[4 * static_cast<std::size_t>(start[order[k]]++)]);
                for (std::uint32_t at = 0; at < count; at += 16) {
                    pk.lanes = static_cast<int>(std::min<std::uint32_t>(16, count - at));
                    const std::uint32_t* q = &sorted[4 * static_cast<std::size_t>(at)];
                    for (int l = 0; l < pk.lanes; ++l)
                        for (int d = 0; d < 4; ++d) pk.word[d][l] = q[4 * l + d];
                    trace();
                }
                trace();
                first += count;
            }
        };
        if (opt.tolerance > 0) {
            replicated_row(rng, out, scratch, wsum, cast_points, exact, figures);
            add_traced(traced_here);
            return;
        }
        std::uint32_t state[4] = {0, 0, 0, 0}, seed[4];
        for (std::uint32_t& sd : seed) sd = static_cast<std::uint32_t>(rng.next() >> 32);
        cast_points(0, opt.rays, state, seed);
        add_traced(traced_here);
        std::sort(touched.begin(), touched.end());
        for (std::uint32_t j : touched) {
            out.col.push_back(j);
            out.val.push_back(acc[j] / wsum);
            acc[j] = 0.0;
        }
        touched.clear();
    }
};

RaycastRowProvider::RaycastRowProvider(const Scene& scene, const RaycastOptions& options)
    : impl_(std::make_unique<Impl>(scene, options)) {}

RaycastRowProvider::~RaycastRowProvider() = default;

std::uint32_t RaycastRowProvider::size() const { return static_cast<std::uint32_t>(impl_->scene.size()); }
std::uint64_t RaycastRowProvider::rays() const { return impl_->opt.rays; }
double RaycastRowProvider::tolerance() const { return impl_->opt.tolerance; }
RaycastStats RaycastRowProvider::stats() const {
    const std::lock_guard lock(impl_->stats_mutex);
    return impl_->totals;
}
void RaycastRowProvider::merge_stats(const RaycastStats& other) { impl_->add(other); }

RayBudget tolerance_rays(double tolerance) {
    const auto pow2_at_least = [](double x) {
        std::uint64_t p = 1;
        while (p < (std::uint64_t{1} << 24) && static_cast<double>(p) < x) p <<= 1;
        return p;
    };
    RayBudget b;
    b.least = std::max<std::uint64_t>(4096, pow2_at_least(3.0 / tolerance));
    b.most = std::max(b.least, std::min<std::uint64_t>(std::uint64_t{1} << 24, pow2_at_least(64.0 / tolerance)));
    return b;
}
unsigned RaycastRowProvider::threads() const { return impl_->threads; }

void RaycastRowProvider::cast_row(std::uint32_t i, SparseRow& out, RowScratch& scratch) const {
    FFCUBE_CHECK_MSG(i < size(), "raycast: row out of range");
    if (scratch.acc.size() != impl_->scene.size()) scratch.acc.assign(impl_->scene.size(), 0.0);
    impl_->row(i, out, scratch);
}

void RaycastRowProvider::compute_rows(std::span<const std::uint32_t> rows, const RowSink& sink) {
    compute_rows_staged(rows, RowStages{}, sink);
}

// Rows through an OrderedRowPool: each worker casts a row and runs the caller's finish on it (the
// near-field correction's analysis and exact values, as much work as the rays on a city), and the
// calling thread passes the rows to the sink in list order while the workers go on. No plans: the
// ray caster samples the whole sender anyway (can_sample_sender is false, so none are asked for).
void RaycastRowProvider::compute_rows_staged(std::span<const std::uint32_t> rows, const RowStages& stages,
                                             const RowSink& sink) {
    for (std::uint32_t r : rows)
        if (r >= size()) throw InternalError(fmt::format("raycast: row {} out of range (n = {})", r, size()));
    if (rows.empty()) return;
    Impl& im = *impl_;
    const std::size_t n = im.scene.size();
    const unsigned T = static_cast<unsigned>(std::min<std::size_t>(im.threads, rows.size()));
    // Per worker: the row's accumulator (n doubles, all zero between rows) and its lists.
    std::vector<RowScratch> scratch(T);
    for (RowScratch& s : scratch) s.acc.assign(n, 0.0);
    const bool refine = im.opt.tolerance > 0;
    const auto make = [&](unsigned w, std::size_t k, std::uint32_t i, SparseRow& out) {
        std::span<const std::pair<std::uint32_t, double>> exact;
        if (refine && stages.exact_entries) exact = stages.exact_entries(k, i);
        RowFigures figures;
        im.row(i, out, scratch[w], exact, &figures);
        if (refine) {
            im.note(figures);
            if (stages.measured) stages.measured(k, i, figures.noise, static_cast<double>(figures.rays));
        }
        if (stages.finish) stages.finish(k, i, out);
    };
    if (T == 1) {
        SparseRow row;
        for (std::size_t k = 0; k < rows.size(); ++k) {
            make(0, k, rows[k], row);
            sink(rows[k], row);
        }
        return;
    }
    OrderedRowPool pool(T, {}, {});
    pool.run(rows, make, sink);
}

}  // namespace ffcube
