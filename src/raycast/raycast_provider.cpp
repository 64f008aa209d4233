#include "ffcube/raycast/raycast_provider.hpp"

#include <embree3/rtcore.h>
#include <glm/geometric.hpp>
#include <fmt/format.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <limits>
#include <numbers>
#include <thread>
#include <vector>

#include "ffcube/core/error.hpp"
#include "ffcube/formfactor/ordered_pool.hpp"
#include "raycast/embree_mesh.hpp"
#include "raycast/sampling.hpp"

namespace ffcube {
namespace {

using namespace raycast_sampling;

// splitmix64: a full-period 64-bit generator that passes BigCrush; seeded per row, so a row's
// numbers depend on (seed, row) only.
struct Rng {
    std::uint64_t s;
    std::uint64_t next() {
        std::uint64_t z = (s += 0x9e3779b97f4a7c15ull);
        z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ull;
        z = (z ^ (z >> 27)) * 0x94d049bb133111ebull;
        return z ^ (z >> 31);
    }
    // Uniform in [0, 1) with 53 random bits.
    double uniform() { return static_cast<double>(next() >> 11) * 0x1.0p-53; }
};

Rng row_rng(std::uint64_t seed, std::uint32_t row) {
    Rng r{seed ^ 0x6a09e667f3bcc909ull};
    r.s ^= r.next() + 0x9e3779b97f4a7c15ull * (static_cast<std::uint64_t>(row) + 1);
    r.next();
    return r;
}

// Up to 16 rays in flight: Embree's packet and, per lane, what the hit's accounting needs.
struct Packet {
    RTCRayHit16 rh;  // RTC_ALIGN(64) members
    alignas(64) int valid[16];
    Vec3 org[16], dir[16];
    double w[16];
    int lanes = 0;
};

}  // namespace

struct RaycastRowProvider::Impl {
    const Scene& scene;
    RaycastOptions opt;
    unsigned threads = 1;
    EmbreeMesh mesh;                          // the scene in Embree coordinates
    std::vector<std::uint8_t> parallelogram;  // per patch: uniform bilinear sampling, weight 1
    mutable std::atomic<std::uint64_t> traced{0};

    Impl(const Scene& s, const RaycastOptions& o) : scene(s), opt(o) {
        if (opt.rays == 0) throw InputError("raycast: the number of rays per row must be at least 1");
        threads = opt.threads ? opt.threads : std::max(1u, std::thread::hardware_concurrency());
        if (scene.size() == 0) return;
        build_embree_mesh(scene, mesh, "raycast");
        parallelogram.resize(scene.size());
        for (std::uint32_t i = 0; i < scene.size(); ++i) {
            const Patch& p = scene.patches[i];
            if (p.count != 4) continue;
            const auto c = scene.patch_vertices(i);
            parallelogram[i] = glm::length(c[0] + c[2] - c[1] - c[3]) <= 1e-12 * p.size;
        }
    }

    // Whether a hit on patch j, for a ray leaving patch i, is a float artefact to pass through:
    // a ray leaving i's front can hit neither i nor a patch in i's plane.
    bool pass_through(std::uint32_t i, std::uint32_t j) const {
        if (i == j) return true;
        const Patch& a = scene.patches[i];
        const Patch& b = scene.patches[j];
        return glm::dot(a.normal, b.normal) > 1.0 - 1e-12 &&
               std::abs(glm::dot(b.centroid - a.centroid, a.normal)) <= 1e-9 * std::max(a.size, b.size);
    }

    // Row i into out; the scratch's acc (size n, all zero) and touched (empty) are left as they
    // were found.
    //
    // Sampling (header comment): the row's rays come in batches of S = m² rays, m = min(⌊√left⌋,
    // kMaxStrataSide), until none are left. In a batch, the k-th ray cast leaves in direction
    // stratum order[k] of an m × m grid over the unit square that the cosine-weighted map takes to
    // the hemisphere (tile_order: neighbouring directions one after another) and starts in
    // stratum perm[k] of an m × m grid over the patch, perm a uniformly random permutation
    // ("padded" stratification: each of the two 2-D projections is stratified, the pairing is
    // random). Every ray's (position, direction) is then uniform on its own, so the row is
    // unbiased for any number of rays; the stratified directions are what lower the error on a
    // receiver seen from most of the sender (a far one), the stratified positions on a near one.
    // Rays are traced 16 at a time (rtcIntersect16) and their hits counted in the order cast.
    void row(std::uint32_t i, SparseRow& out, RowScratch& scratch) const {
        std::vector<double>& acc = scratch.acc;
        std::vector<std::uint32_t>& touched = scratch.touched;
        std::vector<std::uint32_t>& perm = scratch.perm;
        std::vector<std::uint32_t>& order = scratch.order;
        out.clear();
        const Patch& p = scene.patches[i];
        const auto c = scene.patch_vertices(i);
        Rng rng = row_rng(opt.seed, i);
        Vec3 tu, tv;
        orthonormal_basis(p.normal, tu, tv);
        const double offset = std::max(kOriginOffset * p.size * mesh.scale, kMinOffset);
        const Vec3 nrm = p.normal;
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
        const auto add = [&](double u, double v, double r1, double r2) {
            Vec3 x;
            double w = 1.0;
            if (p.count == 3) {
                const double su = std::sqrt(u);  // area-uniform map of the unit square onto a triangle
                x = (1.0 - su) * c[0] + su * (1.0 - v) * c[1] + su * v * c[2];
            } else {
                x = (1 - u) * (1 - v) * c[0] + u * (1 - v) * c[1] + u * v * c[2] + (1 - u) * v * c[3];
                if (!parallelogram[i]) {
                    const Vec3 du = (1 - v) * (c[1] - c[0]) + v * (c[2] - c[3]);
                    const Vec3 dv = (1 - u) * (c[3] - c[0]) + u * (c[2] - c[1]);
                    w = glm::length(glm::cross(du, dv));
                }
            }
            wsum += w;
            const int l = pk.lanes++;
            pk.dir[l] = cosine_direction(r1, r2, tu, tv, nrm);
            pk.org[l] = (x - mesh.center) * mesh.scale + offset * nrm;
            pk.w[l] = w;
            pk.rh.ray.org_x[l] = static_cast<float>(pk.org[l].x);
            pk.rh.ray.org_y[l] = static_cast<float>(pk.org[l].y);
            pk.rh.ray.org_z[l] = static_cast<float>(pk.org[l].z);
            pk.rh.ray.dir_x[l] = static_cast<float>(pk.dir[l].x);
            pk.rh.ray.dir_y[l] = static_cast<float>(pk.dir[l].y);
            pk.rh.ray.dir_z[l] = static_cast<float>(pk.dir[l].z);
        };
        const auto trace = [&]() {
            if (pk.lanes == 0) return;
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
                if (pk.rh.hit.geomID[l] == RTC_INVALID_GEOMETRY_ID) continue;  // left the scene
                std::uint32_t j = mesh.tri_patch[pk.rh.hit.primID[l]];
                // A hit on the ray's own patch (or its plane) can only be float rounding: trace
                // on past it, a few times at most (then the ray is dropped, as if absorbed).
                if (pass_through(i, j))
                    j = first_patch(mesh, ctx, pk.org[l], pk.dir[l], [&](std::uint32_t q) { return pass_through(i, q); },
                                    traced_here, std::nextafter(pk.rh.ray.tfar[l], std::numeric_limits<float>::infinity()),
                                    kRetraces - 1);
                // A front face receives; so does either side of an obstruction-only patch, whose
                // factor is measured only to be left out (Scene::drawn), so that it is not sky.
                if (j != kNoPatch && (glm::dot(pk.dir[l], scene.patches[j].normal) < 0.0 || j >= scene.obstruction_first)) {
                    if (acc[j] == 0.0) touched.push_back(j);
                    acc[j] += pk.w[l];
                }
            }
            pk.lanes = 0;
        };
        for (std::uint64_t left = opt.rays; left > 0;) {
            const std::uint64_t m = strata_side(left);
            const std::uint32_t S = static_cast<std::uint32_t>(m * m);
            perm.resize(S);
            for (std::uint32_t k = 0; k < S; ++k) perm[k] = k;
            for (std::uint32_t k = S; k > 1; --k)  // Fisher–Yates
                std::swap(perm[k - 1], perm[static_cast<std::uint32_t>(rng.next() % k)]);
            if (order.size() != S) tile_order(static_cast<std::uint32_t>(m), order);
            const double inv = 1.0 / static_cast<double>(m);
            for (std::uint32_t k = 0; k < S; ++k) {
                const double u = (static_cast<double>(perm[k] % m) + rng.uniform()) * inv;
                const double v = (static_cast<double>(perm[k] / m) + rng.uniform()) * inv;
                const double r1 = (static_cast<double>(order[k] % m) + rng.uniform()) * inv;
                const double r2 = (static_cast<double>(order[k] / m) + rng.uniform()) * inv;
                add(u, v, r1, r2);
                if (pk.lanes == 16) trace();
            }
            trace();
            left -= S;
        }
        traced.fetch_add(traced_here, std::memory_order_relaxed);
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
unsigned RaycastRowProvider::threads() const { return impl_->threads; }
std::uint64_t RaycastRowProvider::rays_traced() const { return impl_->traced.load(); }

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
    const auto make = [&](unsigned w, std::size_t k, std::uint32_t i, SparseRow& out) {
        im.row(i, out, scratch[w]);
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
