// Sunlit fractions by clipping the shadows' polygons (include/ffcube/gl/sun.hpp,
// sunlit_fractions_clipped; docs/urban.md, "Sun and shade"). No GL: pure CPU, double precision.
//
// Everything is projected along the unit direction s towards the sun onto the plane ⟂ s, with
// axes (e1, e2). For a patch i facing the sun (n_i·s > 1e-9) its projection P_i (one or two
// triangles, as drawn) has the area A_i cos θ_i. A point x of another triangle t shades the point
// of i's plane behind it along −s exactly when x lies on the sun's side of that plane:
//     g_i(x) = (x − c_i)·n_i > 0      (then the ray from x along −s meets i's plane at t = g / (n·s) > 0).
// g_i is affine, so the part of t in front of i's plane is t clipped by g_i > 0 (Sutherland–Hodgman
// on t's corners, the crossing points interpolated along t's edges), a convex polygon whose
// projection C_ti is exactly the shadow t casts on i's plane; the part of it inside P_i is what t
// shades of i. The sunlit part of P_i is P_i minus the union of those C_ti: kept as a list of
// convex pieces, from which each C_ti is subtracted in turn (a convex piece minus a convex polygon
// is at most one convex piece per edge of the polygon: the parts on the outer side of each edge's
// line). The sunlit fraction is Σ area(pieces) / area(P_i): exact up to rounding (relative
// ~1e-13 on the areas), with no pixel and no tolerance. Both faces of every triangle shade, as in
// the item buffer; a triangle in i's own plane (g = 0 within 1e-12 of the scene's size) shades
// nothing, so neighbours on a flat ground do not shade each other.
//
// The candidates t for patch i come from a uniform grid over the projected scene (each triangle
// listed in the cells its projected bounding box covers), tested by bounding box and by g before
// any clipping. Patches are shared among the threads by a fixed stride; each fraction is computed
// by one thread alone in a fixed order, so the result does not depend on the thread count.
#include <fmt/format.h>
#include <glm/geometric.hpp>

#include <algorithm>
#include <array>
#include <cmath>
#include <exception>
#include <limits>
#include <thread>
#include <vector>

#include "ffcube/core/error.hpp"
#include "ffcube/core/timer.hpp"
#include "ffcube/gl/sun.hpp"

namespace ffcube {
namespace {

constexpr double kEdgeOn = 1e-9;  // as the item buffer (sun_buffer.cpp): n·s at most this gets 0
// Triangles per cell of the grid (the lists' length against the cells a receiver reads):
// 4 measured faster than 1 and no slower than 16 on the 22,881-facet city (tools/bench_sun).
constexpr double kTrisPerCell = 4.0;

struct P2 {
    double u, v;
};
using Poly = std::vector<P2>;  // convex, counter-clockwise

double cross(P2 o, P2 a, P2 b) { return (a.u - o.u) * (b.v - o.v) - (a.v - o.v) * (b.u - o.u); }

double area(const Poly& p) {
    double a = 0.0;
    for (std::size_t k = 0; k + 2 < p.size(); ++k) a += cross(p[0], p[k + 1], p[k + 2]);
    return 0.5 * a;
}

// Splits the convex piece `p` by the directed line a→b: `left` gets the part on its left (inside a
// counter-clockwise polygon with that edge), `right` the rest. Points on the line go to both.
void split(const Poly& p, P2 a, P2 b, Poly& left, Poly& right) {
    left.clear();
    right.clear();
    const std::size_t m = p.size();
    double d0 = cross(a, b, p[0]);
    for (std::size_t k = 0; k < m; ++k) {
        const P2 x = p[k], y = p[(k + 1) % m];
        const double d1 = cross(a, b, y);
        if (d0 >= 0.0) left.push_back(x);
        if (d0 <= 0.0) right.push_back(x);
        if ((d0 > 0.0 && d1 < 0.0) || (d0 < 0.0 && d1 > 0.0)) {
            const double t = d0 / (d0 - d1);
            const P2 z{x.u + t * (y.u - x.u), x.v + t * (y.v - x.v)};
            left.push_back(z);
            right.push_back(z);
        }
        d0 = d1;
    }
}

struct Box {
    double u0, v0, u1, v1;
};
Box box_of(const Poly& p) {
    Box b{p[0].u, p[0].v, p[0].u, p[0].v};
    for (const P2& x : p) b = {std::min(b.u0, x.u), std::min(b.v0, x.v), std::max(b.u1, x.u), std::max(b.v1, x.v)};
    return b;
}
bool overlap(const Box& a, const Box& b) { return a.u0 < b.u1 && b.u0 < a.u1 && a.v0 < b.v1 && b.v0 < a.v1; }

// Convex pieces in one flat array (no allocation per piece once the buffers have grown).
struct Pieces {
    std::vector<P2> pts;
    std::vector<std::uint32_t> off{0};  // piece k: pts[off[k] .. off[k + 1])
    std::vector<Box> box;
    std::size_t size() const { return box.size(); }
    void clear() {
        pts.clear();
        off.assign(1, 0);
        box.clear();
    }
    void add(const Poly& p, const Box& b) {
        pts.insert(pts.end(), p.begin(), p.end());
        off.push_back(static_cast<std::uint32_t>(pts.size()));
        box.push_back(b);
    }
    double area() const {
        double a = 0.0;
        for (std::size_t k = 0; k < size(); ++k)
            for (std::uint32_t e = off[k] + 1; e + 1 < off[k + 1]; ++e) a += cross(pts[off[k]], pts[e], pts[e + 1]);
        return 0.5 * a;
    }
};

// Removes the convex, counter-clockwise polygon c (bounding box cb) from every piece of `lit`;
// `out`, `in`, `left`, `right` are scratch.
void subtract(Pieces& lit, const Poly& c, const Box& cb, Pieces& out, Poly& in, Poly& left, Poly& right) {
    out.clear();
    for (std::size_t k = 0; k < lit.size(); ++k) {
        if (!overlap(lit.box[k], cb)) {
            out.pts.insert(out.pts.end(), lit.pts.begin() + lit.off[k], lit.pts.begin() + lit.off[k + 1]);
            out.off.push_back(static_cast<std::uint32_t>(out.pts.size()));
            out.box.push_back(lit.box[k]);
            continue;
        }
        in.assign(lit.pts.begin() + lit.off[k], lit.pts.begin() + lit.off[k + 1]);
        for (std::size_t e = 0; e < c.size() && in.size() >= 3; ++e) {
            split(in, c[e], c[(e + 1) % c.size()], left, right);
            if (right.size() >= 3 && area(right) > 0.0) out.add(right, box_of(right));
            in.swap(left);
        }
        // What is left in `in` lies inside c: shaded.
    }
    std::swap(lit, out);
}

struct Tri {
    std::array<Vec3, 3> x;      // corners
    std::array<P2, 3> p;        // their projections
    Box box;
    std::uint32_t patch;        // drawn patch
};

}  // namespace

SunResult sunlit_fractions_clipped(const Scene& scene, Vec3 towards_sun, unsigned threads) {
    Stopwatch watch;
    SunResult r;
    r.sun = normalized_sun_direction(towards_sun);
    r.renderer = "CPU shadow polygons";
    const Vec3 s = r.sun;
    const Vec3 ref = std::abs(s.z) < 0.9 ? Vec3(0.0, 0.0, 1.0) : Vec3(0.0, 1.0, 0.0);
    const Vec3 e1 = glm::normalize(glm::cross(ref, s)), e2 = glm::cross(s, e1);
    const Scene& drawn = scene.drawn_scene();
    const std::size_t n = scene.size();
    r.fraction.assign(n, 0.0);
    r.cosine.assign(n, 0.0);
    r.pixels.assign(n, 0);

    // Triangles of the drawn scene as drawn by the item buffer: (0,1,2) and, for a quad, (0,2,3).
    // A triangle whose projection has no area (edge-on to the sun) shades nothing and is left out.
    std::vector<Tri> tris;
    tris.reserve(drawn.patches.size() * 2);
    // What the candidates' first tests read, packed: the projected box and the depth (x·s) of the
    // corner nearest the sun. A triangle can shade a point of i only from nearer the sun than
    // i's plane there, so not when its nearest corner is no nearer than i's farthest.
    struct Cull {
        Box box;
        double depth;
    };
    std::vector<Cull> cull;
    cull.reserve(drawn.patches.size() * 2);
    double scale = 0.0;
    Box all{std::numeric_limits<double>::infinity(), std::numeric_limits<double>::infinity(),
            -std::numeric_limits<double>::infinity(), -std::numeric_limits<double>::infinity()};
    for (std::size_t i = 0; i < drawn.patches.size(); ++i) {
        const Patch& p = drawn.patches[i];
        for (std::uint32_t h = 0; h + 2 < p.count; ++h) {
            Tri t;
            t.x = {drawn.positions[p.v[0]], drawn.positions[p.v[h + 1]], drawn.positions[p.v[h + 2]]};
            for (int k = 0; k < 3; ++k) t.p[k] = {glm::dot(t.x[k], e1), glm::dot(t.x[k], e2)};
            t.box = {std::min({t.p[0].u, t.p[1].u, t.p[2].u}), std::min({t.p[0].v, t.p[1].v, t.p[2].v}),
                     std::max({t.p[0].u, t.p[1].u, t.p[2].u}), std::max({t.p[0].v, t.p[1].v, t.p[2].v})};
            all = {std::min(all.u0, t.box.u0), std::min(all.v0, t.box.v0), std::max(all.u1, t.box.u1),
                   std::max(all.v1, t.box.v1)};
            for (const Vec3& x : t.x) scale = std::max({scale, std::abs(x.x), std::abs(x.y), std::abs(x.z)});
            t.patch = static_cast<std::uint32_t>(i);
            tris.push_back(t);
            cull.push_back({t.box, std::max({glm::dot(t.x[0], s), glm::dot(t.x[1], s), glm::dot(t.x[2], s)})});
        }
    }
    for (std::size_t i = 0; i < n; ++i) {
        r.cosine[i] = glm::dot(scene.patches[i].normal, s);
        if (r.cosine[i] > kEdgeOn) ++r.lit_patches;
    }
    if (r.lit_patches == 0 || tris.empty()) {
        r.seconds = watch.seconds();
        return r;
    }
    // Coplanar within this (relative to the scene's coordinates): rounding of g for points of i's plane.
    const double flat = 1e-12 * std::max(scale, 1.0);

    // The grid over the projected bounding box.
    const double W = std::max(all.u1 - all.u0, 1e-300), H = std::max(all.v1 - all.v0, 1e-300);
    const double cells = std::clamp(static_cast<double>(tris.size()) / kTrisPerCell, 1.0, 4.0e6);
    const int gu = static_cast<int>(std::clamp(std::sqrt(cells * W / H), 1.0, 4096.0));
    const int gv = static_cast<int>(std::clamp(std::sqrt(cells * H / W), 1.0, 4096.0));
    const auto cell_range = [&](const Box& b, int& a0, int& a1, int& b0, int& b1) {
        a0 = std::clamp(static_cast<int>((b.u0 - all.u0) / W * gu), 0, gu - 1);
        a1 = std::clamp(static_cast<int>((b.u1 - all.u0) / W * gu), 0, gu - 1);
        b0 = std::clamp(static_cast<int>((b.v0 - all.v0) / H * gv), 0, gv - 1);
        b1 = std::clamp(static_cast<int>((b.v1 - all.v0) / H * gv), 0, gv - 1);
    };
    // Each cell lists its triangles with their box and depth, nearest the sun first: a receiver
    // stops reading a cell at the first triangle no nearer than its own farthest corner.
    // In float, rounded outwards (the box) and up (the depth): the tests stay conservative (they
    // may let a triangle through that cannot shade, never drop one that can) in half the bytes.
    struct Item {
        float u0, v0, u1, v1, depth;
        std::uint32_t tri;
    };
    const auto down = [](double x) {
        const auto f = static_cast<float>(x);
        return static_cast<double>(f) > x ? std::nextafter(f, -std::numeric_limits<float>::infinity()) : f;
    };
    const auto up = [](double x) {
        const auto f = static_cast<float>(x);
        return static_cast<double>(f) < x ? std::nextafter(f, std::numeric_limits<float>::infinity()) : f;
    };
    std::vector<std::uint32_t> start(static_cast<std::size_t>(gu) * gv + 1, 0);
    std::vector<Item> items;
    for (int pass = 0; pass < 2; ++pass) {
        std::vector<std::uint32_t> fill(pass ? start.begin() : start.end() - 1, start.end() - 1);
        for (std::uint32_t t = 0; t < tris.size(); ++t) {
            int a0, a1, b0, b1;
            cell_range(tris[t].box, a0, a1, b0, b1);
            for (int b = b0; b <= b1; ++b)
                for (int a = a0; a <= a1; ++a) {
                    const std::size_t c = static_cast<std::size_t>(b) * gu + a;
                    if (pass == 0)
                        ++start[c + 1];
                    else
                        items[fill[c]++] = {down(cull[t].box.u0), down(cull[t].box.v0), up(cull[t].box.u1),
                                            up(cull[t].box.v1), up(cull[t].depth), t};
                }
        }
        if (pass == 0) {
            for (std::size_t c = 1; c < start.size(); ++c) start[c] += start[c - 1];
            items.resize(start.back());
        }
    }
    for (std::size_t c = 0; c + 1 < start.size(); ++c)
        std::sort(items.begin() + start[c], items.begin() + start[c + 1],
                  [](const Item& a, const Item& b) { return a.depth > b.depth || (a.depth == b.depth && a.tri < b.tri); });

    std::vector<double> projected(n, 0.0), lit_area(n, 0.0);
    // The lit patches in the order of their cells along a Z-curve, so that patches read one after
    // the other share cells (the grid's lists stay in cache); handed out in chunks of kChunk, chunk
    // c to thread c mod threads. The order changes no number: each fraction is computed alone.
    std::vector<std::pair<std::uint64_t, std::uint32_t>> order;
    order.reserve(r.lit_patches);
    for (std::size_t i = 0; i < n; ++i) {
        if (!(r.cosine[i] > kEdgeOn)) continue;
        const P2 c{glm::dot(scene.patches[i].centroid, e1), glm::dot(scene.patches[i].centroid, e2)};
        const auto a = static_cast<std::uint32_t>(std::clamp(static_cast<int>((c.u - all.u0) / W * gu), 0, gu - 1));
        const auto b = static_cast<std::uint32_t>(std::clamp(static_cast<int>((c.v - all.v0) / H * gv), 0, gv - 1));
        std::uint64_t z = 0;
        for (int bit = 0; bit < 16; ++bit) z |= (std::uint64_t{(a >> bit) & 1u} << (2 * bit)) | (std::uint64_t{(b >> bit) & 1u} << (2 * bit + 1));
        order.emplace_back(z, static_cast<std::uint32_t>(i));
    }
    std::sort(order.begin(), order.end());
    constexpr std::size_t kChunk = 64;
    const unsigned used = std::max(1u, threads > 0 ? threads : std::thread::hardware_concurrency());
    std::vector<std::exception_ptr> failure(used);
    const auto part = [&](unsigned w) {
        try {
            std::vector<std::uint32_t> seen(tris.size(), std::numeric_limits<std::uint32_t>::max());
            Pieces lit, scratch;
            Poly c, in, left, right;
            for (std::size_t o = w * kChunk; o < order.size(); o += used * kChunk)
            for (std::size_t i_ = o; i_ < std::min(order.size(), o + kChunk); ++i_) {
                const std::size_t i = order[i_].second;
                const Patch& p = scene.patches[i];
                const Vec3 normal = p.normal, origin = drawn.positions[p.v[0]];
                // P_i: its triangles, counter-clockwise in the image (they face the sun, so they are).
                lit.clear();
                double depth = std::numeric_limits<double>::infinity();  // of i's corner farthest from the sun
                for (std::uint32_t k = 0; k < p.count; ++k) depth = std::min(depth, glm::dot(drawn.positions[p.v[k]], s));
                Box b{std::numeric_limits<double>::infinity(), std::numeric_limits<double>::infinity(),
                      -std::numeric_limits<double>::infinity(), -std::numeric_limits<double>::infinity()};
                for (std::uint32_t h = 0; h + 2 < p.count; ++h) {
                    Poly q;
                    for (const std::uint32_t k : {0u, h + 1, h + 2}) {
                        const Vec3& x = drawn.positions[p.v[k]];
                        q.push_back({glm::dot(x, e1), glm::dot(x, e2)});
                    }
                    if (area(q) < 0.0) std::reverse(q.begin(), q.end());
                    const double a = area(q);
                    if (!(a > 0.0)) continue;
                    projected[i] += a;
                    const Box qb = box_of(q);
                    b = {std::min(b.u0, qb.u0), std::min(b.v0, qb.v0), std::max(b.u1, qb.u1), std::max(b.v1, qb.v1)};
                    lit.add(q, qb);
                }
                if (lit.size() == 0) continue;
                int a0, a1, b0, b1;
                cell_range(b, a0, a1, b0, b1);
                for (int gb = b0; gb <= b1 && lit.size() > 0; ++gb)
                    for (int ga = a0; ga <= a1 && lit.size() > 0; ++ga) {
                        const std::size_t cell = static_cast<std::size_t>(gb) * gu + ga;
                        for (std::uint32_t e = start[cell]; e < start[cell + 1] && lit.size() > 0; ++e) {
                            const Item& it = items[e];
                            if (!(it.depth > depth)) break;
                            const std::uint32_t ti = it.tri;
                            if (!(it.u0 <= b.u1 && b.u0 <= it.u1 && it.v0 <= b.v1 && b.v0 <= it.v1) || seen[ti] == i) continue;
                            seen[ti] = static_cast<std::uint32_t>(i);
                            const Tri& t = tris[ti];
                            if (t.patch == i) continue;
                            // The part of t on the sun's side of i's plane.
                            double g[3];
                            bool front = false;
                            for (int k = 0; k < 3; ++k) {
                                g[k] = glm::dot(t.x[k] - origin, normal);
                                if (g[k] > flat) front = true;
                            }
                            if (!front) continue;
                            c.clear();
                            for (int k = 0; k < 3; ++k) {
                                const int l = (k + 1) % 3;
                                const bool in_k = g[k] > flat, in_l = g[l] > flat;
                                if (in_k) c.push_back(t.p[k]);
                                if (in_k != in_l) {
                                    const double f = (g[k] - flat) / (g[k] - g[l]);
                                    c.push_back({t.p[k].u + f * (t.p[l].u - t.p[k].u), t.p[k].v + f * (t.p[l].v - t.p[k].v)});
                                }
                            }
                            if (c.size() < 3) continue;
                            const double ca = area(c);
                            if (ca == 0.0) continue;
                            if (ca < 0.0) std::reverse(c.begin(), c.end());
                            const Box cb = box_of(c);
                            if (!overlap(cb, b)) continue;
                            subtract(lit, c, cb, scratch, in, left, right);
                            // The box of what is still lit: later candidates are tested against it.
                            if (lit.size() > 0) {
                                b = lit.box[0];
                                for (std::size_t k = 1; k < lit.size(); ++k)
                                    b = {std::min(b.u0, lit.box[k].u0), std::min(b.v0, lit.box[k].v0),
                                         std::max(b.u1, lit.box[k].u1), std::max(b.v1, lit.box[k].v1)};
                            }
                        }
                    }
                lit_area[i] = lit.area();
            }
        } catch (...) {
            failure[w] = std::current_exception();
        }
    };
    std::vector<std::thread> pool;
    for (unsigned w = 1; w < used; ++w) pool.emplace_back(part, w);
    part(0);
    for (std::thread& th : pool) th.join();
    for (const std::exception_ptr& e : failure)
        if (e) std::rethrow_exception(e);

    for (std::size_t i = 0; i < n; ++i) {
        if (!(r.cosine[i] > kEdgeOn) || !(projected[i] > 0.0)) continue;
        double share = lit_area[i] / projected[i];
        if (share > 1.0) {  // rounding only: the pieces lie inside P_i
            ++r.clamped;
            r.max_overshoot = std::max(r.max_overshoot, share - 1.0);
            share = 1.0;
        }
        r.fraction[i] = std::max(0.0, share);
        r.sunlit_projected_area += r.fraction[i] * scene.patches[i].area * r.cosine[i];
    }
    r.seconds = watch.seconds();
    return r;
}

}  // namespace ffcube
