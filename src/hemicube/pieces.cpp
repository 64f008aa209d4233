#include "ffcube/hemicube/pieces.hpp"

#include <glm/common.hpp>
#include <glm/geometric.hpp>

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <tuple>

#include "ffcube/core/error.hpp"
#include "hemicube/point_grid.hpp"

namespace ffcube {

std::vector<std::pair<std::uint32_t, std::uint32_t>> twin_pairs(std::span<const PatchGrid> grids) {
    using Key = std::array<double, 13>;  // count, then the corners sorted, 3 doubles each
    std::map<Key, std::vector<std::uint32_t>> by_corners;
    for (std::uint32_t g = 0; g < grids.size(); ++g) {
        const PatchGrid& pg = grids[g];
        std::vector<Vec3> c(pg.corners.begin(), pg.corners.begin() + pg.count);
        std::sort(c.begin(), c.end(),
                  [](const Vec3& a, const Vec3& b) { return std::tie(a.x, a.y, a.z) < std::tie(b.x, b.y, b.z); });
        Key key{};
        key[0] = pg.count;
        for (std::uint32_t k = 0; k < pg.count; ++k)
            for (int d = 0; d < 3; ++d) key[1 + 3 * k + static_cast<std::size_t>(d)] = c[k][d];
        by_corners[key].push_back(g);
    }
    std::vector<std::pair<std::uint32_t, std::uint32_t>> pairs;
    for (const auto& [key, gs] : by_corners)
        for (std::size_t a = 0; a < gs.size(); ++a)
            for (std::size_t b = a + 1; b < gs.size(); ++b) {
                const PatchGrid &ga = grids[gs[a]], &gb = grids[gs[b]];
                const Vec3 na = polygon_normal(std::span<const Vec3>(ga.corners.data(), ga.count));
                const Vec3 nb = polygon_normal(std::span<const Vec3>(gb.corners.data(), gb.count));
                if (glm::dot(na, nb) < 0) pairs.emplace_back(gs[a], gs[b]);
            }
    return pairs;
}

std::vector<std::uint8_t> find_twins(std::span<const PatchGrid> grids) {
    std::vector<std::uint8_t> has_twin(grids.size(), 0);
    for (const auto& [a, b] : twin_pairs(grids)) has_twin[a] = has_twin[b] = 1;
    return has_twin;
}

bool Enclosure::contains(const Vec3& eye) const {
    for (const Plane& p : planes)
        if (!(glm::dot(p.normal, eye) - p.offset > tolerance)) return false;
    return true;
}

Enclosure find_enclosure(std::span<const PatchGrid> grids, std::span<const std::uint8_t> has_twin) {
    Enclosure en;
    if (grids.size() < 2) return en;
    std::vector<Vec3> pts;  // every corner, once
    for (const PatchGrid& pg : grids) pts.insert(pts.end(), pg.corners.begin(), pg.corners.begin() + pg.count);
    const auto less = [](const Vec3& a, const Vec3& b) { return std::tie(a.x, a.y, a.z) < std::tie(b.x, b.y, b.z); };
    std::sort(pts.begin(), pts.end(), less);
    pts.erase(std::unique(pts.begin(), pts.end()), pts.end());
    Vec3 lo(INFINITY), hi(-INFINITY);
    for (const Vec3& q : pts) {
        lo = glm::min(lo, q);
        hi = glm::max(hi, q);
    }
    const double diag = glm::length(hi - lo);
    if (!(diag > 0) || !std::isfinite(diag)) return en;
    const Vec3 m = glm::max(glm::abs(lo), glm::abs(hi));
    // 1e-10 of the scene, plus the rounding of n·x at the coordinates' magnitude (a scene far
    // from the origin): far below a pixel of any hemicube, and below what a float depth buffer
    // resolves, so nothing the depth test would have decided is decided differently.
    en.tolerance = 1e-10 * diag + 64 * std::numeric_limits<double>::epsilon() * std::max({m.x, m.y, m.z});
    const double tol = en.tolerance;
    // Points that reject most planes at once: the extremes along the axes and the diagonals.
    std::vector<Vec3> probes;
    for (int a = -1; a <= 1; ++a)
        for (int b = -1; b <= 1; ++b)
            for (int c = -1; c <= 1; ++c) {
                if (a == 0 && b == 0 && c == 0) continue;
                const Vec3 dir(a, b, c);
                const auto it = std::min_element(pts.begin(), pts.end(),
                                                 [&](const Vec3& p, const Vec3& q) { return glm::dot(dir, p) < glm::dot(dir, q); });
                probes.push_back(*it);
            }
    // At most this many corner tests in all (an inward-facing sphere of many facets has every
    // facet supporting, each found by a scan of every corner): past it, no more planes.
    std::uint64_t budget = 50'000'000;
    const auto supports = [&](const Vec3& n, double d) {
        for (const Vec3& q : probes)
            if (glm::dot(n, q) - d < -tol) return false;
        bool box = true;  // the box's corners all in front: so is every point
        for (int c = 0; c < 8 && box; ++c) {
            const Vec3 b(c & 1 ? hi.x : lo.x, c & 2 ? hi.y : lo.y, c & 4 ? hi.z : lo.z);
            box = glm::dot(n, b) - d >= -tol;
        }
        if (box) return true;
        if (budget < pts.size()) {
            budget = 0;
            return false;
        }
        budget -= pts.size();
        for (const Vec3& q : pts)
            if (glm::dot(n, q) - d < -tol) return false;
        return true;
    };
    constexpr int kNone = -1;
    std::vector<int> plane_of(grids.size(), kNone);
    const auto on_plane = [&](const PatchGrid& pg, const Enclosure::Plane& pl) {
        for (std::uint32_t k = 0; k < pg.count; ++k)
            if (std::abs(glm::dot(pl.normal, pg.corners[k]) - pl.offset) > tol) return false;
        return true;
    };
    for (std::size_t g = 0; g < grids.size(); ++g) {
        const PatchGrid& pg = grids[g];
        const std::span<const Vec3> c(pg.corners.data(), pg.count);
        const Vec3 n = polygon_normal(c);
        if (glm::dot(n, n) == 0) continue;
        double d = 0;
        for (const Vec3& q : c) d += glm::dot(n, q);
        const Enclosure::Plane own{n, d / static_cast<double>(c.size())};
        if (!on_plane(pg, own)) continue;  // not planar
        for (std::size_t k = 0; k < en.planes.size() && plane_of[g] == kNone; ++k)
            if (glm::dot(n, en.planes[k].normal) > 0 && on_plane(pg, en.planes[k])) plane_of[g] = static_cast<int>(k);
        if (plane_of[g] != kNone || en.planes.size() >= kMaxEnclosurePlanes || budget == 0) continue;
        if (supports(own.normal, own.offset)) {
            plane_of[g] = static_cast<int>(en.planes.size());
            en.planes.push_back(own);
        }
    }
    // A plane another piece lies in (within the tolerance: a plate on the floor, either way up)
    // is left out: there the depth test decided an exact tie.
    std::vector<std::uint8_t> keep(en.planes.size(), 1);
    for (std::size_t g = 0; g < grids.size(); ++g) {
        if (plane_of[g] != kNone) continue;
        for (std::size_t k = 0; k < en.planes.size(); ++k)
            if (keep[k] && on_plane(grids[g], en.planes[k])) keep[k] = 0;
    }
    std::vector<int> renumber(en.planes.size(), kNone);
    std::vector<Enclosure::Plane> kept;
    for (std::size_t k = 0; k < en.planes.size(); ++k)
        if (keep[k]) {
            renumber[k] = static_cast<int>(kept.size());
            kept.push_back(en.planes[k]);
        }
    en.planes = std::move(kept);
    if (en.planes.empty()) return en;
    en.piece.assign(grids.size(), 0);
    for (std::size_t g = 0; g < grids.size(); ++g)
        en.piece[g] = plane_of[g] != kNone && renumber[static_cast<std::size_t>(plane_of[g])] != kNone;
    // The other pieces: in one plane, facing one way or each with a twin?
    en.inner_flat = true;
    bool first = true, one_way = true, twins = true;
    Enclosure::Plane inner;
    for (std::size_t g = 0; g < grids.size() && en.inner_flat; ++g) {
        if (en.piece[g]) continue;
        const PatchGrid& pg = grids[g];
        const Vec3 n = polygon_normal(std::span<const Vec3>(pg.corners.data(), pg.count));
        if (first) {
            inner = {n, glm::dot(n, pg.corners[0])};
            first = false;
        }
        en.inner_flat = glm::dot(n, n) > 0 && on_plane(pg, inner);
        one_way = one_way && glm::dot(n, inner.normal) > 0;
        twins = twins && g < has_twin.size() && has_twin[g];
    }
    en.inner_flat = en.inner_flat && (one_way || twins);
    // Closed: the directed edges a → b of the enclosure pieces, each met once by b → a.
    using Edge = std::array<double, 6>;
    std::vector<Edge> edges, reversed;
    for (std::size_t g = 0; g < grids.size(); ++g) {
        if (!en.piece[g]) continue;
        const PatchGrid& pg = grids[g];
        for (std::uint32_t k = 0; k < pg.count; ++k) {
            const Vec3& a = pg.corners[k];
            const Vec3& b = pg.corners[(k + 1) % pg.count];
            edges.push_back({a.x, a.y, a.z, b.x, b.y, b.z});
            reversed.push_back({b.x, b.y, b.z, a.x, a.y, a.z});
        }
    }
    std::sort(edges.begin(), edges.end());
    std::sort(reversed.begin(), reversed.end());
    en.closed = std::adjacent_find(edges.begin(), edges.end()) == edges.end() && edges == reversed;
    return en;
}

double edge_tolerance(const Vec3& a, const Vec3& b) {
    const Vec3 m = glm::max(glm::abs(a), glm::abs(b));
    return 1e-6 * glm::length(b - a) + 4 * std::numeric_limits<double>::epsilon() * std::max({m.x, m.y, m.z});
}


// Corners of other pieces that lie on a piece's edge strictly between its endpoints, for every
// piece edge, sorted by (piece, edge, t). Corner positions are deduplicated and put in a
// PointGrid whose level-0 cell is the median edge length: a typical edge looks at a few cells
// holding a few corners each, and long edges cost little where no corners lie.
std::vector<EdgeVertex> find_edge_vertices(std::span<const PatchGrid> grids, std::vector<Vec3>& corners) {
    corners.clear();
    std::vector<double> lengths;
    for (const PatchGrid& pg : grids)
        for (std::uint32_t k = 0; k < pg.count; ++k) {
            corners.push_back(pg.corners[k]);
            lengths.push_back(glm::length(pg.corners[(k + 1) % pg.count] - pg.corners[k]));
        }
    const auto lex = [](const Vec3& a, const Vec3& b) {
        return std::tie(a.x, a.y, a.z) < std::tie(b.x, b.y, b.z);
    };
    std::sort(corners.begin(), corners.end(), lex);
    corners.erase(std::unique(corners.begin(), corners.end()), corners.end());
    std::vector<EdgeVertex> found;
    if (lengths.empty()) return found;
    const auto mid = lengths.begin() + static_cast<std::ptrdiff_t>(lengths.size() / 2);
    std::nth_element(lengths.begin(), mid, lengths.end());
    if (!(*mid > 0)) return found;  // cannot happen: pieces have area
    const PointGrid grid(corners, *mid);

    std::vector<EdgeVertex> on_edge;
    for (std::uint32_t g = 0; g < grids.size(); ++g) {
        const PatchGrid& pg = grids[g];
        for (std::uint32_t k = 0; k < pg.count; ++k) {
            const Vec3 a = pg.corners[k], b = pg.corners[(k + 1) % pg.count];
            const Vec3 d = b - a;
            const double len2 = glm::dot(d, d), len = std::sqrt(len2);
            // See edge_tolerance: 1e-9 of the edge was too tight for six-digit OBJ coordinates (test
            // TJunctionsWithSixDigitCoordinatesLeakNothing); moving the piece's outline through
            // such a corner changes it by that much, far below a pixel.
            const double tol = edge_tolerance(a, b);
            on_edge.clear();
            grid.near_segment(a, b, tol, [&](std::uint32_t at) {
                const Vec3 w = corners[at] - a;
                const double t = glm::dot(w, d) / len2;
                if (t * len <= tol || (1 - t) * len <= tol) return;  // an endpoint, or beyond
                const Vec3 off = w - d * t;
                if (glm::dot(off, off) > tol * tol) return;
                on_edge.push_back(EdgeVertex{g, k, t, at});
            });
            // A corner seen from two cells (or two steps) counts once.
            std::sort(on_edge.begin(), on_edge.end(),
                      [](const EdgeVertex& u, const EdgeVertex& v) { return std::tie(u.t, u.at) < std::tie(v.t, v.at); });
            for (std::size_t i = 0; i < on_edge.size(); ++i)
                if (i == 0 || on_edge[i].at != on_edge[i - 1].at) found.push_back(on_edge[i]);
        }
    }
    return found;
}

// Triangulates a convex piece whose boundary (vertex slots, CCW from the front) has T-vertices
// inside some edges, into boundary.size() − 2 triangles none of which has its three vertices on
// one edge of the piece (zero area: float rounding could turn it into a back face). on_edges[i]:
// the piece edges vertex i lies on (two for a corner, one for a T-vertex), which is what decides
// collinearity, exactly. A strip from corner 0: the part still to cover is the chain l, l+1 ... r
// closed by the diagonal (r, l); each step cuts the triangle (l, l+1, r) or (l, r−1, r) off it,
// the one whose new diagonal is shorter among those that have area and leave a chain with a
// corner strictly inside (one with area) or of two vertices (done). One of the two always
// qualifies: a chain with an inner corner has area, so its first and last vertices share no
// edge with both their neighbours unless the diagonal lies along that edge, which the strip
// never makes; and if neither cut left an inner corner, l + 1 = r − 1 would be the only one.
void triangulate_boundary(const std::vector<std::uint32_t>& b, const std::vector<std::uint8_t>& on_edges,
                          const std::vector<Vec3>& pos, std::vector<std::uint32_t>& tris) {
    const std::size_t n = b.size();
    const auto fwd = [n](std::size_t from, std::size_t to) { return (to + n - from) % n; };
    const auto is_corner = [&](std::size_t i) { return (on_edges[i] & (on_edges[i] - 1)) != 0; };
    // next_corner[i]: the first corner after position i, going forward.
    std::vector<std::size_t> next_corner(n);
    std::size_t c = 0;  // position 0 is corner 0
    for (std::size_t k = 2 * n; k-- > 0;) {
        const std::size_t i = k % n;
        next_corner[i] = c;
        if (is_corner(i)) c = i;
    }
    const auto has_area = [&](std::size_t from, std::size_t to) {  // the chain from .. to, closed
        return fwd(from, to) == 1 || fwd(from, next_corner[from]) < fwd(from, to);
    };
    std::size_t l = 0, r = n - 1;
    while (fwd(l, r) >= 2) {
        const std::size_t l1 = (l + 1) % n, r1 = (r + n - 1) % n;
        const bool cut_l = (on_edges[l] & on_edges[l1] & on_edges[r]) == 0 && has_area(l1, r);
        const bool cut_r = (on_edges[l] & on_edges[r1] & on_edges[r]) == 0 && has_area(l, r1);
        FFCUBE_CHECK_MSG(cut_l || cut_r, "triangulating a piece with T-vertices");
        const auto len2 = [&](std::size_t i, std::size_t j) {
            const Vec3 d = pos[b[i]] - pos[b[j]];
            return glm::dot(d, d);
        };
        if (cut_l && (!cut_r || len2(l1, r) <= len2(l, r1))) {
            tris.insert(tris.end(), {b[l], b[l1], b[r]});
            l = l1;
        } else {
            tris.insert(tris.end(), {b[l], b[r1], b[r]});
            r = r1;
        }
    }
}

// Why T-vertices: see pieces.hpp. They take the other piece's corner position bit for bit, so
// after the shared double → float transform in the GL worker both pieces' edges end at the very
// same vertices.
//   The polygon (convex, with collinear vertices on its edges) is cut into as many triangles as
// it has vertices less two, none of zero area (triangulate_boundary). Plane coordinates are
// affine in position, so the new vertices' are computed like the corners'. Pieces without
// T-vertices keep exactly their old triangles (c0, c1, c2), (c0, c2, c3), in the old order:
// their pixels do not change. Culling still uses the corners only (the polygon is the same
// piece), and finding the T-vertices is done once per scene (find_edge_vertices).
ScenePieces prepare_pieces(std::span<const PatchGrid> grids) {
    ScenePieces sp;
    const std::size_t ng = grids.size();
    sp.gpu.reserve(ng);
    sp.first.reserve(ng + 1);
    sp.tri_first.reserve(ng + 1);
    std::vector<Vec3> corners;
    const std::vector<EdgeVertex> tv = find_edge_vertices(grids, corners);
    std::size_t next_tv = 0;
    std::vector<std::uint32_t> boundary;
    std::vector<std::uint8_t> on_edges;
    sp.tri_first.push_back(0);
    for (std::uint32_t g = 0; g < ng; ++g) {
        const PatchGrid& pg = grids[g];
        // An orthonormal basis of the piece's plane; coordinates relative to corner 0 in double,
        // so far-off scenes lose nothing before the conversion to float.
        const Vec3 n = polygon_normal(std::span<const Vec3>(pg.corners.data(), pg.count));
        const Vec3 e1 = glm::normalize(pg.corners[1] - pg.corners[0]);
        const Vec3 e2 = glm::cross(n, e1);
        double qd[4][2];
        float q[4][2];
        for (int k = 0; k < 4; ++k) {
            const Vec3 d = pg.corners[static_cast<std::size_t>(k)] - pg.corners[0];
            qd[k][0] = glm::dot(d, e1);
            qd[k][1] = glm::dot(d, e2);
            q[k][0] = static_cast<float>(qd[k][0]);
            q[k][1] = static_cast<float>(qd[k][1]);
        }
        // Affine pieces carry their cell coordinates as the vertex parameter, so the fragment
        // shader only takes their floor (a perspective-correct interpolation of an affine
        // function of the plane is exact up to float rounding, as the plane coordinates it
        // replaces are): triangles (s, t) = k × barycentric, and quads that are parallelograms
        // (count 5 on the GPU side) (u nu, v nv). Other quads keep plane coordinates and the
        // shader's inverse bilinear. The drawing time at N = 256 was 80% this per-pixel solve
        // (docs/benchmarks.md).
        std::uint32_t kind = pg.count;
        double inv[2][2] = {};  // plane coordinates → cell coordinates, affine pieces
        {
            const double size = std::max(std::abs(qd[1][0]) + std::abs(qd[1][1]), std::abs(qd[3][0]) + std::abs(qd[3][1]));
            const double gx = qd[2][0] - qd[1][0] - qd[3][0], gy = qd[2][1] - qd[1][1] - qd[3][1];
            // Columns: the cell axes' plane vectors (c1 − c0 and c2 − c0 or c3 − c0) over nu, nv.
            double a[2][2];
            if (pg.count == 3) {
                a[0][0] = qd[1][0] / pg.nu; a[1][0] = qd[1][1] / pg.nu;
                a[0][1] = qd[2][0] / pg.nu; a[1][1] = qd[2][1] / pg.nu;
            } else {
                a[0][0] = qd[1][0] / pg.nu; a[1][0] = qd[1][1] / pg.nu;
                a[0][1] = qd[3][0] / pg.nv; a[1][1] = qd[3][1] / pg.nv;
                // A parallelogram to 1e-9 of its size: the bilinear map is then affine to well
                // below float rounding of the cell coordinates (≤ 1e-9 × nu of a cell). Or to a
                // few ulps of its coordinates: a small piece far from the origin cannot be told
                // from a parallelogram by more than its corners' own rounding.
                double mag = 0;
                for (std::uint32_t k = 0; k < 4; ++k)
                    for (int d = 0; d < 3; ++d) mag = std::max(mag, std::abs(pg.corners[k][d]));
                if (std::abs(gx) + std::abs(gy) <= 1e-9 * size + 8 * std::numeric_limits<double>::epsilon() * mag) kind = 5;
            }
            const double det = a[0][0] * a[1][1] - a[0][1] * a[1][0];
            inv[0][0] = a[1][1] / det; inv[0][1] = -a[0][1] / det;
            inv[1][0] = -a[1][0] / det; inv[1][1] = a[0][0] / det;
        }
        const bool affine = kind != 4;
        sp.has_kind[kind] = true;
        if (pg.nu != 1 || pg.nv != 1) sp.single_cell = false;
        const auto add_slot = [&](const Vec3& p) {
            const Vec3 d = p - pg.corners[0];
            const double x = glm::dot(d, e1), y = glm::dot(d, e2);
            sp.pos.push_back(p);
            if (affine) {
                sp.param.push_back(static_cast<float>(inv[0][0] * x + inv[0][1] * y));
                sp.param.push_back(static_cast<float>(inv[1][0] * x + inv[1][1] * y));
            } else {
                sp.param.push_back(static_cast<float>(x));
                sp.param.push_back(static_cast<float>(y));
            }
            sp.grid.push_back(g);
            sp.info.insert(sp.info.end(), {kind, pg.nu, pg.nv, pg.first_patch});
            return static_cast<std::uint32_t>(sp.pos.size() - 1);
        };
        sp.gpu.push_back(GpuGrid{{q[1][0], q[1][1]}, {q[2][0], q[2][1]}, {q[3][0], q[3][1]}, kind, pg.nu, pg.nv,
                                 pg.first_patch});
        const auto base = static_cast<std::uint32_t>(sp.pos.size());
        sp.first.push_back(base);
        for (std::uint32_t k = 0; k < pg.count; ++k) add_slot(pg.corners[k]);
        if (next_tv < tv.size() && tv[next_tv].g == g) {
            // The boundary, CCW: each corner, then the T-vertices inside the edge it starts;
            // with, per vertex, the piece edges it lies on (bit k: edge k, corner k → k + 1).
            boundary.clear();
            on_edges.clear();
            for (std::uint32_t k = 0; k < pg.count; ++k) {
                boundary.push_back(base + k);
                on_edges.push_back(static_cast<std::uint8_t>((1u << k) | (1u << ((k + pg.count - 1) % pg.count))));
                for (; next_tv < tv.size() && tv[next_tv].g == g && tv[next_tv].k == k; ++next_tv) {
                    boundary.push_back(add_slot(corners[tv[next_tv].at]));
                    on_edges.push_back(static_cast<std::uint8_t>(1u << k));
                }
            }
            triangulate_boundary(boundary, on_edges, sp.pos, sp.tris);
        }
        sp.tri_first.push_back(static_cast<std::uint32_t>(sp.tris.size()));
    }
    sp.first.push_back(static_cast<std::uint32_t>(sp.pos.size()));
    sp.has_twin = find_twins(grids);
    sp.enclosure = find_enclosure(grids, sp.has_twin);
    sp.bvh = PieceBvh(PieceBvh::piece_boxes(grids));
    return sp;
}

}  // namespace ffcube
