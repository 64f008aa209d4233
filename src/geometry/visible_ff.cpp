// Exact form factors past a few convex occluders (see visible_ff.hpp).
#include "ffcube/geometry/visible_ff.hpp"

#include <glm/geometric.hpp>

#include <algorithm>
#include <array>
#include <cmath>
#include <numbers>

#include "ffcube/geometry/analytic.hpp"
#include "ffcube/geometry/quadrature.hpp"
#include "ffcube/geometry/tolerance.hpp"

namespace ffcube {

namespace {

// Visible pieces beyond this many mean shadows cut R into a fine mosaic, which the callers'
// "a few occluders" never make (8 quads over one receiver: tens): the kernel gives up (NaN) rather
// than spend unbounded work, and the area kernel reports not converged.
constexpr std::size_t kMaxPieces = 4096;

// Sutherland–Hodgman: the part of `in` where sign · dot(m, v − o) ≥ 0.
void clip_keep(std::span<const Vec3> in, const Vec3& o, const Vec3& m, double sign, std::vector<Vec3>& out) {
    out.clear();
    const std::size_t k = in.size();
    for (std::size_t e = 0; e < k; ++e) {
        const Vec3 &a = in[e], &b = in[(e + 1) % k];
        const double da = sign * glm::dot(a - o, m), db = sign * glm::dot(b - o, m);
        if (da >= 0) out.push_back(a);
        if ((da > 0 && db < 0) || (da < 0 && db > 0)) out.push_back(a + (b - a) * (da / (da - db)));
    }
}

double max_extent(std::span<const Vec3> poly) {
    double s = 0;
    for (const Vec3& v : poly) s = std::max(s, glm::length(v - poly[0]));
    return s;
}

}  // namespace

bool polygon_is_convex(std::span<const Vec3> poly) {
    if (poly.size() < 3) return false;
    if (poly.size() == 3) return true;
    const Vec3 n = newell_vector(poly);
    const double scale = max_extent(poly);
    const std::size_t k = poly.size();
    for (std::size_t e = 0; e < k; ++e) {
        const Vec3 a = poly[(e + 1) % k] - poly[e], b = poly[(e + 2) % k] - poly[(e + 1) % k];
        // a turn against the polygon's orientation beyond rounding (1e-12 of the size²·|n|)
        if (glm::dot(glm::cross(a, b), n) < -1e-12 * scale * scale * glm::length(n)) return false;
    }
    return true;
}

double ff_point_visible_polygon(const Vec3& p, const Vec3& n, std::span<const Vec3> receiver,
                                std::span<const std::vector<Vec3>> occluders, std::size_t* pieces_out) {
    if (pieces_out) *pieces_out = 0;
    const Vec3 nr = polygon_normal(receiver);
    const Vec3 r0 = polygon_centroid(receiver);
    const double size = max_extent(receiver);
    const double coord = std::max({max_abs_coordinate(receiver), std::abs(p.x), std::abs(p.y), std::abs(p.z)});
    // d(x): height above R's plane on its front. p in (or behind) the plane sees nothing of it.
    const double dp = glm::dot(nr, p - r0);
    if (dp <= geometric_tolerance(1e-12, size, coord)) return 0.0;
    std::vector<std::vector<Vec3>> pieces{std::vector<Vec3>(receiver.begin(), receiver.end())}, next;
    std::vector<Vec3> slab, tmp, outside, inside;
    std::vector<Vec3> planes;
    for (const std::vector<Vec3>& occ : occluders) {
        if (pieces.empty()) break;
        // The part of the occluder strictly between R's plane and p's level: a segment from p to
        // R's plane meets only heights in (0, dp). The top is kept 1e-9·dp below p's level: what
        // lies above it blocks only directions within 1e-9 of R's plane, which reach R's plane
        // ≥ 1e9 × (its distance from p) away, beyond any receiver unless it passes within 1e-9 of
        // the receiver's size of p.
        clip_keep(occ, r0, nr, 1.0, tmp);
        if (tmp.size() < 3) continue;
        clip_keep(tmp, r0 + nr * (dp * (1.0 - 1e-9)), nr, -1.0, slab);
        if (slab.size() < 3) continue;
        const Vec3 c = polygon_centroid(slab);
        const Vec3 no = newell_vector(slab);
        const double osize = max_extent(slab);
        const double len = glm::length(no);
        if (!(len > 0)) continue;
        // p in the occluder's plane: its cone is flat and blocks a set of measure zero.
        if (std::abs(glm::dot(no / len, p - c)) <= geometric_tolerance(1e-12, osize, coord)) continue;
        // The cone from p over the occluder: the planes through p and each edge, normals pointing
        // into the cone (towards the occluder's centroid, inside a convex polygon).
        planes.clear();
        for (std::size_t e = 0; e < slab.size(); ++e) {
            Vec3 m = glm::cross(slab[e] - p, slab[(e + 1) % slab.size()] - p);
            const double ml = glm::length(m);
            if (!(ml > 0)) continue;  // an edge of zero length
            m /= ml;
            if (glm::dot(m, c - p) < 0) m = -m;
            planes.push_back(m);
        }
        next.clear();
        for (const std::vector<Vec3>& piece : pieces) {
            // piece = (outside plane 1) ∪ (inside 1, outside 2) ∪ … ∪ (inside all: shadow)
            tmp = piece;
            for (const Vec3& m : planes) {
                clip_keep(tmp, p, m, -1.0, outside);
                if (outside.size() >= 3) next.push_back(outside);
                clip_keep(tmp, p, m, 1.0, inside);
                std::swap(tmp, inside);
                if (tmp.size() < 3) break;
            }
        }
        std::swap(pieces, next);
        if (pieces.size() > kMaxPieces) return std::nan("");
    }
    if (pieces_out) *pieces_out = pieces.size();
    // All pieces keep R's orientation, so their Lambert sums share a sign: the sum of their
    // absolute values is the absolute value of the sum (the pieces' shared edges cancel).
    double f = 0;
    for (const std::vector<Vec3>& piece : pieces) {
        clip_keep(piece, p, n, 1.0, tmp);
        if (tmp.size() >= 3) f += ff_point_polygon_unclipped(p, n, tmp);
    }
    return f;
}

namespace {

struct Cell {
    std::array<Vec3, 3> t;
    std::array<double, 4> child{};  // the rule on each of the 4 midpoint children
    double value = 0;               // Σ child
    double error = 0;               // |Σ child − rule on t|
};

struct AreaIntegrator {
    Vec3 n;
    std::span<const Vec3> receiver;
    std::span<const std::vector<Vec3>> occluders;
    // 4 points: with an odd count the middle node lies on the children's common edges, and a
    // kink along such a line errs alike in the rule and its children; their difference then
    // understated the error 8-fold on the L-shaped room (4 points: the estimate bounds it).
    GaussRule g = gauss_legendre(4);
    std::uint64_t points = 0;
    bool failed = false;

    // Collapsed (Duffy) 4 × 4 Gauss rule on a triangle: p = a + u (b − a) + u v (c − b),
    // dA = 2 A u du dv on [0, 1]².
    double rule(const std::array<Vec3, 3>& t) {
        const double twice_area = glm::length(glm::cross(t[1] - t[0], t[2] - t[0]));
        double s = 0;
        for (std::size_t a = 0; a < g.x.size(); ++a)
            for (std::size_t b = 0; b < g.x.size(); ++b) {
                const double u = 0.5 * (g.x[a] + 1), v = 0.5 * (g.x[b] + 1);
                const Vec3 p = t[0] + u * (t[1] - t[0]) + u * v * (t[2] - t[1]);
                const double f = ff_point_visible_polygon(p, n, receiver, occluders);
                ++points;
                if (!std::isfinite(f)) failed = true;
                s += 0.25 * g.w[a] * g.w[b] * u * twice_area * (std::isfinite(f) ? f : 0.0);
            }
        return s;
    }
    static std::array<std::array<Vec3, 3>, 4> children(const std::array<Vec3, 3>& t) {
        const Vec3 ab = 0.5 * (t[0] + t[1]), bc = 0.5 * (t[1] + t[2]), ca = 0.5 * (t[2] + t[0]);
        return {{{t[0], ab, ca}, {ab, t[1], bc}, {ca, bc, t[2]}, {ab, bc, ca}}};
    }
    Cell make(const std::array<Vec3, 3>& t, double coarse) {
        Cell c{t};
        const auto ch = children(t);
        for (std::size_t k = 0; k < 4; ++k) c.child[k] = rule(ch[k]);
        c.value = c.child[0] + c.child[1] + c.child[2] + c.child[3];
        c.error = std::abs(c.value - coarse);
        return c;
    }
};

}  // namespace

std::uint64_t visible_ff_min_points(std::size_t sender_vertices, const VisibleFFOptions& options) {
    if (sender_vertices < 3) return 0;
    std::uint64_t cells = sender_vertices - 2;
    for (int d = 0; d < options.min_depth; ++d) cells *= 4;
    return cells * 5 * 16;
}

VisibleFFResult ff_polygon_visible_polygon(std::span<const Vec3> sender, std::span<const Vec3> receiver,
                                           std::span<const std::vector<Vec3>> occluders, const VisibleFFOptions& options) {
    VisibleFFResult r;
    const double area = polygon_area(sender);
    if (!(area > 0) || sender.size() < 3) return r;
    AreaIntegrator in{polygon_normal(sender), receiver, occluders};
    auto by_error = [](const Cell& a, const Cell& b) { return a.error < b.error; };
    std::vector<Cell> heap;
    // Start from each fan triangle split options.min_depth times: a cell whose rule and
    // children's rules all miss a small visible (or shadowed) region estimates its error as 0
    // (the sender's points beyond a corner's reach see nothing), so the first cells must be fine
    // enough to notice where the integrand changes.
    std::vector<std::array<Vec3, 3>> start, finer;
    for (std::size_t k = 1; k + 1 < sender.size(); ++k) start.push_back({sender[0], sender[k], sender[k + 1]});
    for (int d = 0; d < options.min_depth; ++d) {
        finer.clear();
        for (const auto& t : start)
            for (const auto& c : AreaIntegrator::children(t)) finer.push_back(c);
        std::swap(start, finer);
    }
    for (const auto& t : start) {
        heap.push_back(in.make(t, in.rule(t)));
        std::push_heap(heap.begin(), heap.end(), by_error);
    }
    const double budget = options.tolerance * area;
    auto total_error = [&] {
        double e = 0;
        for (const Cell& c : heap) e += c.error;
        return e;
    };
    double error = total_error();
    while (error > budget && in.points + 256 <= options.max_points && !in.failed) {
        std::pop_heap(heap.begin(), heap.end(), by_error);
        const Cell cell = heap.back();
        heap.pop_back();
        const auto ch = AreaIntegrator::children(cell.t);
        for (std::size_t k = 0; k < 4; ++k) {
            heap.push_back(in.make(ch[k], cell.child[k]));
            std::push_heap(heap.begin(), heap.end(), by_error);
        }
        error = total_error();
    }
    double value = 0;
    for (const Cell& c : heap) value += c.value;
    r.f = value / area;
    r.error = error / area;
    r.points = in.points;
    r.converged = !in.failed && error <= budget;
    if (in.failed) r.f = std::nan("");
    return r;
}

}  // namespace ffcube
