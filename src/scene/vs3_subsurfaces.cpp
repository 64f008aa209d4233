#include "vs3_subsurfaces.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <glm/geometric.hpp>

#include "ffcube/geometry/tolerance.hpp"

namespace ffcube::detail {
namespace {

double size_of(std::span<const Vec3> poly) { return polygon_max_edge(poly); }

// The two sides of the plane through `a` with unit normal `m` (the plane holds the base's normal):
// `inside` where m · (x − a) ≥ −tol, `outside` where ≤ tol; a vertex within tol of the plane goes
// to both, and an edge that crosses it adds the crossing point, computed once, to both.
void split(const std::vector<Vec3>& poly, const Vec3& a, const Vec3& m, double tol, std::vector<Vec3>& inside,
           std::vector<Vec3>& outside) {
    inside.clear();
    outside.clear();
    for (std::size_t i = 0; i < poly.size(); ++i) {
        const Vec3& p = poly[i];
        const Vec3& q = poly[(i + 1) % poly.size()];
        const double dp = glm::dot(m, p - a), dq = glm::dot(m, q - a);
        if (dp >= -tol) inside.push_back(p);
        if (dp <= tol) outside.push_back(p);
        if ((dp > tol && dq < -tol) || (dp < -tol && dq > tol)) {
            const Vec3 x = p + (q - p) * (dp / (dp - dq));
            inside.push_back(x);
            outside.push_back(x);
        }
    }
}

// Drops repeated and collinear vertices (within tol); what is left of a sliver has < 3.
std::vector<Vec3> cleaned(const std::vector<Vec3>& poly, double tol) {
    std::vector<Vec3> out = poly;
    bool changed = true;
    while (changed && out.size() >= 3) {
        changed = false;
        for (std::size_t i = 0; i < out.size() && out.size() >= 3; ++i) {
            const Vec3& prev = out[(i + out.size() - 1) % out.size()];
            const Vec3& next = out[(i + 1) % out.size()];
            const Vec3& p = out[i];
            const double base_len = glm::length(next - prev);
            // distance of p from the line prev–next (or from prev when they coincide)
            const double off = base_len > 0.0 ? glm::length(glm::cross(next - prev, p - prev)) / base_len : glm::length(p - prev);
            if (off <= tol) {
                out.erase(out.begin() + static_cast<std::ptrdiff_t>(i));
                changed = true;
            }
        }
    }
    if (out.size() < 3) out.clear();
    return out;
}

}  // namespace

std::string subsurface_problem(std::span<const Vec3> base, std::span<const Vec3> sub, bool same_facing) {
    const Vec3 n = polygon_normal(base);
    const Vec3 ns = polygon_normal(sub);
    const double size = size_of(base);
    const double tol = geometric_tolerance(kPlanarityTolerance, size, std::max(max_abs_coordinate(base), max_abs_coordinate(sub)));
    for (const Vec3& v : sub) {
        const double off = glm::dot(n, v - base[0]);
        if (std::abs(off) > tol)
            return fmt::format("a vertex ({}, {}, {}) is {:.3g} off the base's plane (at most {:.3g}: it must lie in that plane)", v.x,
                               v.y, v.z, off, tol);
    }
    const double facing = glm::dot(n, ns);
    if (same_facing && facing < 0.999) return "it does not face the way its base faces (a subsurface must face the same way)";
    if (!same_facing && facing > -0.999)
        return "it does not face its base (a mask or null surface faces the opposite way, toward the base)";
    for (const Vec3& v : sub)
        for (std::size_t k = 0; k < base.size(); ++k) {
            const Vec3& a = base[k];
            const Vec3& b = base[(k + 1) % base.size()];
            const Vec3 inward = glm::cross(n, b - a);
            const double d = glm::dot(inward, v - a) / glm::length(inward);
            if (d < -tol)
                return fmt::format("a vertex ({}, {}, {}) lies {:.3g} outside the base (it must lie wholly inside its base)", v.x, v.y,
                                   v.z, -d);
        }
    return {};
}

double convex_overlap_area(std::span<const Vec3> a, std::span<const Vec3> b) {
    const Vec3 n = polygon_normal(a);
    std::vector<Vec3> hole(b.begin(), b.end());
    if (glm::dot(polygon_normal(hole), n) < 0.0) std::reverse(hole.begin(), hole.end());
    std::vector<Vec3> rest(a.begin(), a.end()), inside, outside;
    for (std::size_t k = 0; k < hole.size() && rest.size() >= 3; ++k) {
        const Vec3 e = glm::cross(n, hole[(k + 1) % hole.size()] - hole[k]);
        if (glm::length(e) == 0.0) continue;
        split(rest, hole[k], glm::normalize(e), 0.0, inside, outside);
        rest = inside;
    }
    return rest.size() >= 3 ? polygon_area(rest) : 0.0;
}

std::vector<std::vector<Vec3>> cut_holes(std::span<const Vec3> base, const std::vector<std::vector<Vec3>>& holes) {
    const std::vector<Vec3> base_poly(base.begin(), base.end());
    if (holes.empty()) return {base_poly};
    const Vec3 n = polygon_normal(base);
    const double size = size_of(base);
    const double tol = geometric_tolerance(1e-9, size, max_abs_coordinate(base));
    const double min_area = tol * size;
    std::vector<std::vector<Vec3>> pieces = {base_poly};
    std::vector<Vec3> inside, outside;
    for (std::vector<Vec3> hole : holes) {
        if (glm::dot(polygon_normal(hole), n) < 0.0) std::reverse(hole.begin(), hole.end());
        std::vector<std::vector<Vec3>> next;
        for (const std::vector<Vec3>& piece : pieces) {
            // Peel the piece edge by edge of the hole: what lies outside an edge is a piece of the
            // rest; what lies inside every edge is the piece's part of the hole, dropped.
            std::vector<std::vector<Vec3>> peeled;
            std::vector<Vec3> rest = piece;
            for (std::size_t k = 0; k < hole.size() && !rest.empty(); ++k) {
                const Vec3& a = hole[k];
                const Vec3& b = hole[(k + 1) % hole.size()];
                const Vec3 e = glm::cross(n, b - a);
                if (glm::length(e) == 0.0) continue;  // a repeated corner: no edge
                split(rest, a, glm::normalize(e), tol, inside, outside);
                std::vector<Vec3> out = cleaned(outside, tol);
                if (!out.empty() && polygon_area(out) > min_area) peeled.push_back(std::move(out));
                rest = cleaned(inside, tol);
            }
            if (rest.empty() || polygon_area(rest) <= min_area) {
                next.push_back(piece);  // the hole does not reach into this piece
                continue;
            }
            for (auto& p : peeled) next.push_back(std::move(p));
        }
        pieces = std::move(next);
    }
    // Convex polygons of more than 4 vertices as a fan of quads (and a last triangle) from the
    // first vertex: each is convex, being the hull of vertices of a convex polygon.
    std::vector<std::vector<Vec3>> out;
    for (const std::vector<Vec3>& p : pieces) {
        std::size_t i = 1;
        while (i + 1 < p.size()) {
            if (i + 2 < p.size()) {
                out.push_back({p[0], p[i], p[i + 1], p[i + 2]});
                i += 2;
            } else {
                out.push_back({p[0], p[i], p[i + 1]});
                i += 1;
            }
        }
    }
    return out;
}

}  // namespace ffcube::detail
