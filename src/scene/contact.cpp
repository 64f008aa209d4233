// Cutting receiver faces along contact polygons (scene/contact.hpp, docs/adaptive.md).
#include "ffcube/scene/contact.hpp"

#include <fmt/format.h>
#include <glm/geometric.hpp>
#include <glm/vec2.hpp>

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <utility>

#include "ffcube/geometry/polygon.hpp"
#include "ffcube/geometry/tolerance.hpp"

namespace ffcube {
namespace {

using P2 = glm::dvec2;
using Poly2 = std::vector<P2>;

double cross2(P2 a, P2 b) { return a.x * b.y - a.y * b.x; }

double max_component(const Vec3& v) { return std::max({v.x, v.y, v.z}); }

double area2(const Poly2& p) {
    double s = 0.0;
    for (std::size_t i = 0; i < p.size(); ++i) s += cross2(p[i], p[(i + 1) % p.size()]);
    return 0.5 * s;
}

// A face's polygon (repeated consecutive vertices dropped, as the mesher does) and what the
// receiver test needs of it.
struct FaceInfo {
    std::vector<Vec3> poly;
    Vec3 normal{0.0};
    double size = 0.0;
    Vec3 lo{0.0}, hi{0.0};
    bool planar_convex = false;  // a possible receiver
};

// Convex and counter-clockwise (every turn ≥ −tolerance; one winding, checked by a fan).
bool convex_ccw(const Poly2& p, double tolerance) {
    const std::size_t n = p.size();
    if (n < 3) return false;
    for (std::size_t i = 0; i < n; ++i)
        if (cross2(p[i] - p[(i + n - 1) % n], p[(i + 1) % n] - p[i]) < -tolerance) return false;
    for (std::size_t i = 1; i + 1 < n; ++i)
        if (cross2(p[i] - p[0], p[i + 1] - p[0]) < -tolerance) return false;
    return true;
}

FaceInfo face_info(const ObjModel& model, const ObjFace& face) {
    FaceInfo f;
    for (const std::uint32_t v : face.v)
        if (f.poly.empty() || model.positions[v] != f.poly.back()) f.poly.push_back(model.positions[v]);
    while (f.poly.size() > 1 && f.poly.back() == f.poly.front()) f.poly.pop_back();
    if (f.poly.size() < 3) return f;
    f.size = polygon_max_edge(f.poly);
    f.normal = polygon_normal(f.poly);
    f.lo = f.hi = f.poly[0];
    for (const Vec3& p : f.poly) f.lo = glm::min(f.lo, p), f.hi = glm::max(f.hi, p);
    const double area = polygon_area(f.poly);
    if (!(area > 1e-12 * f.size * f.size) || polygon_planarity_deviation(f.poly) > kPlanarityTolerance * f.size) return f;
    Vec3 u, w;
    orthonormal_basis(f.normal, u, w);
    Poly2 q;
    for (const Vec3& p : f.poly) q.push_back({glm::dot(p - f.poly[0], u), glm::dot(p - f.poly[0], w)});
    f.planar_convex = convex_ccw(q, 1e-12 * f.size * f.size);
    return f;
}

// Splits the convex polygon `poly` by the directed line a → b into its left part (the inside of a
// counter-clockwise polygon's edge) and its right part; vertices within `tol` of the line go to
// both, so that neighbouring parts share them exactly.
void split_by_line(const Poly2& poly, P2 a, P2 b, double tol, Poly2& left, Poly2& right) {
    left.clear();
    right.clear();
    const P2 d = b - a;
    const double len = std::sqrt(glm::dot(d, d));
    const auto side = [&](P2 p) {
        const double s = cross2(d, p - a) / len;
        return std::abs(s) <= tol ? 0.0 : s;
    };
    for (std::size_t i = 0; i < poly.size(); ++i) {
        const P2 p = poly[i], q = poly[(i + 1) % poly.size()];
        const double sp = side(p), sq = side(q);
        if (sp >= 0.0) left.push_back(p);
        if (sp <= 0.0) right.push_back(p);
        if ((sp > 0.0 && sq < 0.0) || (sp < 0.0 && sq > 0.0)) {
            const P2 x = p + (q - p) * (sp / (sp - sq));
            left.push_back(x);
            right.push_back(x);
        }
    }
}

// Drops repeated vertices (within tol); empty when no area is left.
Poly2 cleaned(const Poly2& p, double tol, double min_area) {
    Poly2 out;
    for (const P2& v : p)
        if (out.empty() || glm::distance(out.back(), v) > tol) out.push_back(v);
    while (out.size() > 1 && glm::distance(out.back(), out.front()) <= tol) out.pop_back();
    if (out.size() < 3 || !(area2(out) > min_area)) out.clear();
    return out;
}

Poly2 clip_to(const Poly2& poly, const Poly2& convex, double tol, double min_area) {
    Poly2 rest = poly, left, right;
    for (std::size_t k = 0; k < convex.size() && !rest.empty(); ++k) {
        split_by_line(rest, convex[k], convex[(k + 1) % convex.size()], tol, left, right);
        rest = cleaned(left, tol, min_area);
    }
    return rest;
}

// Closed loops of 3-D edges chained end to start within tol; edges that branch or do not close
// make no loop.
std::vector<std::vector<Vec3>> chain_loops(std::vector<std::pair<Vec3, Vec3>> edges, double tol) {
    const auto same = [tol](const Vec3& a, const Vec3& b) { return glm::distance(a, b) <= tol; };
    std::vector<std::pair<Vec3, Vec3>> unique;
    for (const auto& e : edges) {
        bool dup = false;
        for (const auto& u : unique)
            dup = dup || (same(e.first, u.first) && same(e.second, u.second)) || (same(e.first, u.second) && same(e.second, u.first));
        if (!dup) unique.push_back(e);
    }
    std::vector<bool> used(unique.size(), false);
    std::vector<std::vector<Vec3>> loops;
    for (std::size_t s = 0; s < unique.size(); ++s) {
        if (used[s]) continue;
        used[s] = true;
        std::vector<Vec3> loop{unique[s].first};
        Vec3 cur = unique[s].second;
        bool closed = false;
        for (;;) {
            if (loop.size() >= 3 && same(cur, loop[0])) {
                closed = true;
                break;
            }
            loop.push_back(cur);
            std::size_t found = unique.size(), count = 0;
            Vec3 next{0.0};
            for (std::size_t k = 0; k < unique.size(); ++k) {
                if (used[k]) continue;
                if (same(unique[k].first, cur)) found = k, next = unique[k].second, ++count;
                else if (same(unique[k].second, cur)) found = k, next = unique[k].first, ++count;
            }
            if (count != 1) break;
            used[found] = true;
            cur = next;
        }
        if (closed) loops.push_back(std::move(loop));
    }
    return loops;
}

struct ObjectContacts {
    std::vector<std::vector<Vec3>> bottoms;       // coplanar faces facing the other way
    std::vector<std::pair<Vec3, Vec3>> edges;     // edges in the plane of faces standing on it
};

struct Piece {
    Poly2 poly;
    bool covered = false;
};

// Faces by the cells of a uniform grid that their boxes meet, so that a receiver looks only at
// the faces whose boxes could meet its own (the scan over all faces was F² box tests: 5.2e8 and
// about 3 s on a city of 22,881 facets). About one cell a face over the scene's box, each axis
// at least the mean face extent (a face meets few cells); a face meeting more than kMaxCells
// cells (a ground plane under a city) goes to a list every query returns.
class FaceGrid {
public:
    explicit FaceGrid(const std::vector<FaceInfo>& info) {
        Vec3 lo(std::numeric_limits<double>::max()), hi(std::numeric_limits<double>::lowest());
        double extent = 0.0;
        std::size_t n = 0;
        for (const FaceInfo& f : info) {
            if (f.poly.size() < 3) continue;
            lo = glm::min(lo, f.lo), hi = glm::max(hi, f.hi);
            extent += max_component(f.hi - f.lo);
            ++n;
        }
        if (n == 0) return;
        lo_ = lo;
        const Vec3 span = glm::max(hi - lo, Vec3(1e-300));
        const double volume_cell = std::cbrt(span.x * span.y * span.z / static_cast<double>(n));
        const double h = std::max({extent / static_cast<double>(n), volume_cell, max_component(span) / 1024.0});
        for (int a = 0; a < 3; ++a) dims_[a] = std::clamp(static_cast<int>(span[a] / h) + 1, 1, 1024);
        for (int a = 0; a < 3; ++a) inv_[a] = dims_[a] / span[a];
        cells_.resize(static_cast<std::size_t>(dims_[0]) * dims_[1] * dims_[2]);
        for (std::uint32_t i = 0; i < info.size(); ++i) {
            const FaceInfo& f = info[i];
            if (f.poly.size() < 3) continue;
            int a0[3], a1[3];
            range(f.lo, f.hi, 0.0, a0, a1);
            const std::size_t count = static_cast<std::size_t>(a1[0] - a0[0] + 1) * (a1[1] - a0[1] + 1) * (a1[2] - a0[2] + 1);
            if (count > kMaxCells) {
                big_.push_back(i);
                continue;
            }
            for (int z = a0[2]; z <= a1[2]; ++z)
                for (int y = a0[1]; y <= a1[1]; ++y)
                    for (int x = a0[0]; x <= a1[0]; ++x) cells_[index(x, y, z)].push_back(i);
        }
        stamp_.assign(info.size(), 0);
    }
    // The faces whose cells meet the box [lo − tol, hi + tol], ascending, each once.
    void query(const Vec3& lo, const Vec3& hi, double tol, std::vector<std::uint32_t>& out) {
        out.clear();
        if (cells_.empty()) return;
        ++now_;
        const auto take = [&](std::uint32_t i) {
            if (stamp_[i] != now_) stamp_[i] = now_, out.push_back(i);
        };
        for (const std::uint32_t i : big_) take(i);
        int a0[3], a1[3];
        range(lo, hi, tol, a0, a1);
        for (int z = a0[2]; z <= a1[2]; ++z)
            for (int y = a0[1]; y <= a1[1]; ++y)
                for (int x = a0[0]; x <= a1[0]; ++x)
                    for (const std::uint32_t i : cells_[index(x, y, z)]) take(i);
        std::sort(out.begin(), out.end());
    }

private:
    static constexpr std::size_t kMaxCells = 4096;
    std::size_t index(int x, int y, int z) const {
        return (static_cast<std::size_t>(z) * dims_[1] + y) * dims_[0] + x;
    }
    void range(const Vec3& lo, const Vec3& hi, double tol, int a0[3], int a1[3]) const {
        for (int a = 0; a < 3; ++a) {
            a0[a] = std::clamp(static_cast<int>(std::floor((lo[a] - tol - lo_[a]) * inv_[a])), 0, dims_[a] - 1);
            a1[a] = std::clamp(static_cast<int>(std::floor((hi[a] + tol - lo_[a]) * inv_[a])), 0, dims_[a] - 1);
        }
    }
    Vec3 lo_{0.0}, inv_{0.0};
    int dims_[3] = {1, 1, 1};
    std::vector<std::vector<std::uint32_t>> cells_;
    std::vector<std::uint32_t> big_;
    std::vector<std::uint32_t> stamp_;
    std::uint32_t now_ = 0;
};

}  // namespace

ContactCutStats cut_contacts(ObjModel& model) {
    ContactCutStats stats;
    // A contact is between two objects: with one object (an STL file) there is nothing to cut.
    if (model.objects.size() < 2) return stats;
    std::vector<FaceInfo> info;
    info.reserve(model.faces.size());
    for (const ObjFace& f : model.faces) info.push_back(face_info(model, f));
    FaceGrid grid(info);
    // Per object, its faces in ascending order.
    std::vector<std::vector<std::uint32_t>> object_faces(model.objects.size());
    for (std::uint32_t gi = 0; gi < model.faces.size(); ++gi) object_faces[model.faces[gi].object].push_back(gi);
    std::vector<std::uint32_t> candidates, near_objects;
    std::vector<ObjFace> out;
    out.reserve(model.faces.size());
    for (std::size_t ri = 0; ri < model.faces.size(); ++ri) {
        const ObjFace& rface = model.faces[ri];
        const FaceInfo& r = info[ri];
        if (!r.planar_convex) {
            out.push_back(rface);
            continue;
        }
        const double tol = geometric_tolerance(kPlanarityTolerance, r.size, max_abs_coordinate(r.poly));
        const double min_area = 1e-12 * r.size * r.size;  // the mesher's degenerate-face bound
        const Vec3 p0 = r.poly[0], n = r.normal;
        Vec3 u, w;
        orthonormal_basis(n, u, w);
        const auto to2 = [&](const Vec3& p) { return P2(glm::dot(p - p0, u), glm::dot(p - p0, w)); };
        // Objects with a face whose box meets the receiver's; all their faces count (a contact
        // polygon may reach beyond the receiver: it is clipped to it). An object of many faces
        // near many receivers (all buildings of a city as one object on a ground of many
        // facets) still costs faces × its faces.
        grid.query(r.lo, r.hi, tol, candidates);
        near_objects.clear();
        for (const std::uint32_t gi : candidates) {
            const FaceInfo& g = info[gi];
            if (g.poly.size() < 3 || glm::any(glm::lessThan(g.hi + tol, r.lo)) || glm::any(glm::greaterThan(g.lo - tol, r.hi)))
                continue;
            if (model.faces[gi].object != rface.object) near_objects.push_back(model.faces[gi].object);
        }
        std::sort(near_objects.begin(), near_objects.end());
        near_objects.erase(std::unique(near_objects.begin(), near_objects.end()), near_objects.end());
        std::map<std::uint32_t, ObjectContacts> by_object;  // ordered: deterministic
        for (const std::uint32_t object : near_objects) {
            for (const std::uint32_t gi : object_faces[object]) {
                const FaceInfo& g = info[gi];
                if (g.poly.size() < 3) continue;
                std::vector<double> d(g.poly.size());
                bool coplanar = true, front = true;
                for (std::size_t k = 0; k < d.size(); ++k) {
                    d[k] = glm::dot(g.poly[k] - p0, n);
                    coplanar = coplanar && std::abs(d[k]) <= tol;
                    front = front && d[k] >= -tol;
                }
                ObjectContacts& c = by_object[model.faces[gi].object];
                if (coplanar) {
                    if (glm::dot(g.normal, n) < 0.0) c.bottoms.push_back(g.poly);
                    continue;
                }
                if (!front) continue;
                for (std::size_t k = 0; k < d.size(); ++k) {
                    const std::size_t k1 = (k + 1) % d.size();
                    if (std::abs(d[k]) <= tol && std::abs(d[k1]) <= tol) c.edges.emplace_back(g.poly[k], g.poly[k1]);
                }
            }
        }
        std::vector<Poly2> footprints;
        std::vector<Vec3> snap;  // vertices the cut pieces should reuse exactly
        for (const Vec3& p : r.poly) snap.push_back(p);
        for (auto& [object, c] : by_object) {
            const std::vector<std::vector<Vec3>> loops = c.bottoms.empty() ? chain_loops(c.edges, tol) : c.bottoms;
            for (const std::vector<Vec3>& loop : loops) {
                Poly2 h;
                for (const Vec3& p : loop) h.push_back(to2(p));
                if (area2(h) < 0.0) std::reverse(h.begin(), h.end());
                h = cleaned(h, tol, min_area);
                if (h.empty()) continue;
                if (!convex_ccw(h, tol * r.size)) {
                    if (++stats.skipped <= 10)  // the rest are counted only
                        stats.notes.push_back(fmt::format("{}:{}: the contact of object '{}' is not convex; not cut", model.source,
                                                      rface.line, model.objects[object]));
                    continue;
                }
                footprints.push_back(std::move(h));
                for (const Vec3& p : loop) snap.push_back(p);
            }
        }
        Poly2 rpoly;
        for (const Vec3& p : r.poly) rpoly.push_back(to2(p));
        std::vector<Piece> pieces{{rpoly, false}};
        std::size_t contacts = 0;
        Poly2 left, right;
        for (const Poly2& h : footprints) {
            std::vector<Piece> next;
            bool cuts = false;  // h splits a piece: it is a contact line on this face
            for (const Piece& piece : pieces) {
                if (clip_to(piece.poly, h, tol, min_area).empty()) {
                    next.push_back(piece);
                    continue;
                }
                const std::size_t before = next.size();
                // piece \ h as convex parts: outside edge k, inside edges 0..k−1; the rest is inside h.
                Poly2 rest = piece.poly;
                for (std::size_t k = 0; k < h.size() && !rest.empty(); ++k) {
                    split_by_line(rest, h[k], h[(k + 1) % h.size()], tol, left, right);
                    Poly2 outside = cleaned(right, tol, min_area);
                    if (!outside.empty()) next.push_back({std::move(outside), piece.covered});
                    rest = cleaned(left, tol, min_area);
                }
                if (!rest.empty()) next.push_back({std::move(rest), true});
                cuts = cuts || next.size() - before > 1;
            }
            // A face wholly inside a contact polygon (a block's bottom face on the floor) is not cut.
            if (cuts) {
                ++contacts;
                pieces = std::move(next);
            }
        }
        if (contacts == 0) {
            out.push_back(rface);
            continue;
        }
        stats.contacts += contacts;
        ++stats.receivers;
        stats.faces += pieces.size();
        for (const Piece& piece : pieces) {
            ObjFace f = rface;
            f.v.clear();
            for (const P2& q : piece.poly) {
                Vec3 p = p0 + q.x * u + q.y * w;
                for (const Vec3& s : snap)
                    if (glm::distance(to2(s), q) <= tol) {
                        p = s;
                        break;
                    }
                f.v.push_back(static_cast<std::uint32_t>(model.positions.size()));
                model.positions.push_back(p);
            }
            if (piece.covered) stats.covered_area += area2(piece.poly);
            out.push_back(std::move(f));
        }
    }
    model.faces = std::move(out);
    return stats;
}

}  // namespace ffcube
