#include "ffcube/gl/hemicube_provider.hpp"

#include <fmt/format.h>
#include <glm/common.hpp>
#include <glm/geometric.hpp>

#include <algorithm>
#include <array>
#include <bit>
#include <cmath>
#include <condition_variable>
#include <cstdlib>
#include <exception>
#include <limits>
#include <map>
#include <mutex>
#include <thread>
#include <tuple>
#include <unordered_map>
#include <fstream>
#include <cstring>
#include <cstdio>

#include <sys/socket.h>
#include <sys/wait.h>
#include <unistd.h>

#include "ffcube/core/error.hpp"
#include "ffcube/core/timer.hpp"
#include "ffcube/geometry/quadrature.hpp"
#include "ffcube/hemicube/frame.hpp"
#include "ffcube/hemicube/layout.hpp"
#include "gl/gl_api.hpp"
#include "gl/objects.hpp"

namespace ffcube::shaders {
extern const std::string_view item_vert;
extern const std::string_view item_frag;
}  // namespace ffcube::shaders

namespace ffcube {
namespace {

constexpr std::uint32_t kBackFace = 0xFFFFFFFFu;

// What the fragment shader reads per piece (std430 layout of 'struct Grid' in item.frag).
struct GpuGrid {
    float q1[2], q2[2], q3[2];
    std::uint32_t count, nu, nv, first;
};
static_assert(sizeof(GpuGrid) == 40);

// The scene's mesher pieces, made once and shared read-only by all workers. Each piece owns a
// run of vertex slots: its corners first (count of them), then the T-vertices on its edges (see
// prepare_pieces). Per slot: world position, static plane coordinates and the piece index.
struct ScenePieces {
    std::vector<GpuGrid> gpu;
    std::vector<Vec3> pos;             // 1 per vertex slot: world position
    std::vector<float> param;          // 2 per vertex slot
    std::vector<std::uint32_t> grid;   // 1 per vertex slot
    std::vector<std::uint32_t> info;   // 4 per vertex slot: its piece's kind, nu, nv, first patch
    std::array<bool, 6> has_kind{};    // some piece is of this kind (3, 4 or 5)
    std::vector<std::uint32_t> first;  // per piece, plus one at the end: its first vertex slot
    // Per piece, plus one at the end: its range in 'tris'. An empty range means the piece is
    // drawn as its corners say: (c0, c1, c2), and (c0, c2, c3) for a quad.
    std::vector<std::uint32_t> tri_first;
    std::vector<std::uint32_t> tris;   // vertex slot triples, CCW from the front
    // Per piece: another piece has exactly its corners and faces the other way (one side of a
    // two-sided plate made of two one-sided faces). When such a piece shows its back, its twin
    // shows its front over exactly the same pixels: the back is not drawn at all, so the two
    // can never z-fight, however steeply they are seen (a depth offset could not settle that
    // without letting things behind edge-on back faces through).
    std::vector<std::uint8_t> has_twin;
};

// Marks the pieces that have a twin (see ScenePieces::has_twin): same corner set, opposite side.
void find_twins(const Scene& scene, ScenePieces& sp) {
    using Key = std::array<double, 13>;  // count, then the corners sorted, 3 doubles each
    std::map<Key, std::vector<std::uint32_t>> by_corners;
    for (std::uint32_t g = 0; g < scene.grids.size(); ++g) {
        const PatchGrid& pg = scene.grids[g];
        std::vector<Vec3> c(pg.corners.begin(), pg.corners.begin() + pg.count);
        std::sort(c.begin(), c.end(),
                  [](const Vec3& a, const Vec3& b) { return std::tie(a.x, a.y, a.z) < std::tie(b.x, b.y, b.z); });
        Key key{};
        key[0] = pg.count;
        for (std::uint32_t k = 0; k < pg.count; ++k)
            for (int d = 0; d < 3; ++d) key[1 + 3 * k + static_cast<std::size_t>(d)] = c[k][d];
        by_corners[key].push_back(g);
    }
    sp.has_twin.assign(scene.grids.size(), 0);
    for (const auto& [key, gs] : by_corners)
        for (std::size_t a = 0; a < gs.size(); ++a)
            for (std::size_t b = a + 1; b < gs.size(); ++b) {
                const PatchGrid &ga = scene.grids[gs[a]], &gb = scene.grids[gs[b]];
                const Vec3 na = polygon_normal(std::span<const Vec3>(ga.corners.data(), ga.count));
                const Vec3 nb = polygon_normal(std::span<const Vec3>(gb.corners.data(), gb.count));
                if (glm::dot(na, nb) < 0) sp.has_twin[gs[a]] = sp.has_twin[gs[b]] = 1;
            }
}

// A corner of another piece strictly inside edge k (corner k → k + 1) of piece g.
struct EdgeVertex {
    std::uint32_t g, k;
    double t;            // position along the edge, 0 at corner k, 1 at corner k + 1
    std::uint32_t at;    // index into the unique corner positions
};

// Points bucketed in a hierarchy of uniform grids: level 0 has cells of size h, level L cells of
// 2^L × 2^L × 2^L level-0 cells. near_segment() walks a segment at the level where it takes a
// step or two and goes down a level only where a step's box holds a point, so a segment costs
// about its length in level-0 cells where points lie near it, and a few steps per level through
// empty space, however long it is. Keys are hashes of cell coordinates: cells that share a key
// merely have their points tested in vain.
class PointGrid {
public:
    PointGrid(const std::vector<Vec3>& points, double h) : h_(h) {
        origin_ = points.empty() ? Vec3(0.0) : points.front();
        for (const Vec3& p : points) origin_ = glm::min(origin_, p);
        std::int64_t top = 1;
        std::vector<std::array<std::int64_t, 3>> cells(points.size());
        for (std::size_t i = 0; i < points.size(); ++i) {
            cells[i] = {cell(points[i].x, origin_.x), cell(points[i].y, origin_.y), cell(points[i].z, origin_.z)};
            top = std::max({top, cells[i][0], cells[i][1], cells[i][2]});
        }
        levels_ = std::min(static_cast<int>(std::bit_width(static_cast<std::uint64_t>(top))) + 1, 62);
        count_ = static_cast<std::uint32_t>(points.size());
        by_cell_.resize(points.size());
        for (std::size_t i = 0; i < points.size(); ++i)
            by_cell_[i] = {key(cells[i], 0), static_cast<std::uint32_t>(i)};
        std::sort(by_cell_.begin(), by_cell_.end());
        ranges_.reserve(by_cell_.size());
        for (std::uint32_t i = 0; i < by_cell_.size();) {
            std::uint32_t j = i;
            while (j < by_cell_.size() && by_cell_[j].first == by_cell_[i].first) ++j;
            ranges_.emplace(by_cell_[i].first, std::pair{i, j});
            i = j;
        }
        // The occupied cells of each level, from those of the level below (fewer and fewer).
        occupied_.resize(static_cast<std::size_t>(levels_));
        std::sort(cells.begin(), cells.end());
        cells.erase(std::unique(cells.begin(), cells.end()), cells.end());
        for (int l = 1; l < levels_; ++l) {
            for (auto& c : cells)
                for (auto& v : c) v >>= 1;
            std::sort(cells.begin(), cells.end());
            cells.erase(std::unique(cells.begin(), cells.end()), cells.end());
            auto& occ = occupied_[static_cast<std::size_t>(l)];
            for (const auto& c : cells) occ.push_back(key(c, 0));  // c is already level l's
            std::sort(occ.begin(), occ.end());
        }
    }

    // Calls f(index) for every point within the box of the segment a → b widened by tol (and
    // for some others, some of them more than once). A tolerance wider than a cell (an edge a
    // billion times the cell, or coordinates some 1e15 times it) is met by testing every point.
    template <typename F>
    void near_segment(const Vec3& a, const Vec3& b, double tol, F&& f) const {
        if (!(tol <= h_)) {
            for (std::uint32_t i = 0; i < count_; ++i) f(i);
            return;
        }
        const double len = glm::length(b - a);
        int level = 0;
        while (level + 1 < levels_ && std::ldexp(h_, level) < len) ++level;
        visit(level, a, b, 0.0, 1.0, tol, f);
    }

private:
    std::int64_t cell(double x, double o) const { return static_cast<std::int64_t>(std::floor((x - o) / h_)); }
    static std::uint64_t key(const std::array<std::int64_t, 3>& c, int level) {
        std::uint64_t k = static_cast<std::uint64_t>(c[0] >> level) * 0x9E3779B97F4A7C15ull;
        k ^= static_cast<std::uint64_t>(c[1] >> level) * 0xC2B2AE3D27D4EB4Full + (k << 6) + (k >> 2);
        k ^= static_cast<std::uint64_t>(c[2] >> level) * 0x165667B19E3779F9ull + (k << 6) + (k >> 2);
        return k;
    }
    // The part s0..s1 of a → b, at this level: in steps of at most one cell, each step's box
    // widened by tol.
    template <typename F>
    void visit(int level, const Vec3& a, const Vec3& b, double s0, double s1, double tol, F& f) const {
        const Vec3 d = b - a;
        const double cell_size = std::ldexp(h_, level);
        const auto steps = static_cast<std::size_t>(std::max(1.0, std::ceil((s1 - s0) * glm::length(d) / cell_size)));
        for (std::size_t i = 0; i < steps; ++i) {
            const double t0 = s0 + (s1 - s0) * static_cast<double>(i) / static_cast<double>(steps);
            const double t1 = i + 1 == steps ? s1 : s0 + (s1 - s0) * static_cast<double>(i + 1) / static_cast<double>(steps);
            const Vec3 p0 = a + d * t0, p1 = a + d * t1;
            const Vec3 lo = glm::min(p0, p1) - tol, hi = glm::max(p0, p1) + tol;
            const std::array<std::int64_t, 3> c0 = {cell(lo.x, origin_.x), cell(lo.y, origin_.y), cell(lo.z, origin_.z)};
            const std::array<std::int64_t, 3> c1 = {cell(hi.x, origin_.x), cell(hi.y, origin_.y), cell(hi.z, origin_.z)};
            bool any = false;
            for (std::int64_t x = c0[0] >> level; x <= c1[0] >> level && !any; ++x)
                for (std::int64_t y = c0[1] >> level; y <= c1[1] >> level && !any; ++y)
                    for (std::int64_t z = c0[2] >> level; z <= c1[2] >> level && !any; ++z) {
                        const std::uint64_t k = key({x, y, z}, 0);  // already shifted
                        if (level > 0) {
                            const auto& occ = occupied_[static_cast<std::size_t>(level)];
                            any = std::binary_search(occ.begin(), occ.end(), k);
                            continue;
                        }
                        const auto it = ranges_.find(k);
                        if (it == ranges_.end()) continue;
                        for (std::uint32_t j = it->second.first; j < it->second.second; ++j) f(by_cell_[j].second);
                    }
            if (any) visit(level - 1, a, b, t0, t1, tol, f);
        }
    }

    double h_;
    Vec3 origin_{0.0};
    int levels_ = 1;
    std::uint32_t count_ = 0;
    std::vector<std::pair<std::uint64_t, std::uint32_t>> by_cell_;  // level 0: (key, point), sorted
    std::unordered_map<std::uint64_t, std::pair<std::uint32_t, std::uint32_t>> ranges_;  // key → by_cell_ run
    std::vector<std::vector<std::uint64_t>> occupied_;             // levels ≥ 1: sorted keys
};

// Corners of other pieces that lie on a piece's edge strictly between its endpoints, for every
// piece edge, sorted by (piece, edge, t). Corner positions are deduplicated and put in a
// PointGrid whose level-0 cell is the median edge length: a typical edge looks at a few cells
// holding a few corners each, and long edges cost little where no corners lie.
std::vector<EdgeVertex> find_edge_vertices(const Scene& scene, std::vector<Vec3>& corners) {
    corners.clear();
    std::vector<double> lengths;
    for (const PatchGrid& pg : scene.grids)
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
    for (std::uint32_t g = 0; g < scene.grids.size(); ++g) {
        const PatchGrid& pg = scene.grids[g];
        for (std::uint32_t k = 0; k < pg.count; ++k) {
            const Vec3 a = pg.corners[k], b = pg.corners[(k + 1) % pg.count];
            const Vec3 d = b - a;
            const double len2 = glm::dot(d, d), len = std::sqrt(len2);
            const Vec3 m = glm::max(glm::abs(a), glm::abs(b));
            // 1e-6 of the edge: OBJ files written with 6 significant digits put a corner meant to
            // lie inside an oblique edge up to ~1e-7 of the edge off it, and missed it cracked
            // (test TJunctionsWithSixDigitCoordinatesLeakNothing; 1e-9 was too tight). Moving
            // the piece's outline through such a corner changes it by that much, far below a pixel.
            const double tol = 1e-6 * len + 4 * std::numeric_limits<double>::epsilon() * std::max({m.x, m.y, m.z});
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

// Pieces meet in T-junctions where a corner of one lies inside an edge of another (a wall split
// at a height its neighbours are not, a floor of faces of different widths). Rasterized from
// different endpoints, the long edge and the short ones beside it do not cover the same pixels:
// pixel-size cracks open between them, and hemicubes see through closed walls. So each piece is
// drawn as the polygon of its corners and of the other pieces' corners that lie strictly inside
// its edges (within 1e-6 of the edge length, plus a few ulps of the coordinates): those
// T-vertices take the other piece's corner position bit for bit, so after the shared
// double → float transform in Worker::render both pieces' edges end at the very same vertices,
// and the rasterizer's rules for shared edges leave no gap and no overlap.
//   The polygon (convex, with collinear vertices on its edges) is cut into as many triangles as
// it has vertices less two, none of zero area (triangulate_boundary). Plane coordinates are
// affine in position, so the new vertices' are computed like the corners'. Pieces without
// T-vertices keep exactly their old triangles (c0, c1, c2), (c0, c2, c3), in the old order:
// their pixels do not change. Culling still uses the corners only (the polygon is the same
// piece), and finding the T-vertices is done once per scene (find_edge_vertices).
ScenePieces prepare_pieces(const Scene& scene) {
    ScenePieces sp;
    const std::size_t ng = scene.grids.size();
    sp.gpu.reserve(ng);
    sp.first.reserve(ng + 1);
    sp.tri_first.reserve(ng + 1);
    std::vector<Vec3> corners;
    const std::vector<EdgeVertex> tv = find_edge_vertices(scene, corners);
    std::size_t next_tv = 0;
    std::vector<std::uint32_t> boundary;
    std::vector<std::uint8_t> on_edges;
    sp.tri_first.push_back(0);
    for (std::uint32_t g = 0; g < ng; ++g) {
        const PatchGrid& pg = scene.grids[g];
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
                // below float rounding of the cell coordinates (≤ 1e-9 × nu of a cell).
                if (std::abs(gx) + std::abs(gy) <= 1e-9 * size) kind = 5;
            }
            const double det = a[0][0] * a[1][1] - a[0][1] * a[1][0];
            inv[0][0] = a[1][1] / det; inv[0][1] = -a[0][1] / det;
            inv[1][0] = -a[1][0] / det; inv[1][1] = a[0][0] / det;
        }
        const bool affine = kind != 4;
        sp.has_kind[kind] = true;
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
    find_twins(scene, sp);
    return sp;
}

// Column-major 4×4 for glUniformMatrix4fv: reversed-Z, infinite far plane, near at 'near'
// (eye units), times the face's view rotation (rows right, up, -forward).
std::array<float, 16> face_matrix(const FaceSpec& f, double near) {
    const FaceFrustum& fr = f.frustum;
    // Projection rows (acting on eye coordinates):
    //   x' = 2/(r-l) x + (r+l)/(r-l) z,  y' = 2/(t-b) y + (t+b)/(t-b) z,  z' = near,  w' = -z
    // so NDC depth = near / distance: with glClipControl(ZERO_TO_ONE) and GL_GREATER, float depth
    // keeps about 7 significant digits at every distance.
    const double P[4][4] = {{2 / (fr.right - fr.left), 0, (fr.right + fr.left) / (fr.right - fr.left), 0},
                            {0, 2 / (fr.top - fr.bottom), (fr.top + fr.bottom) / (fr.top - fr.bottom), 0},
                            {0, 0, 0, near},
                            {0, 0, -1, 0}};
    const Vec3 rows[3] = {f.right, f.up, -f.forward};
    double V[4][4] = {};
    for (int r = 0; r < 3; ++r) {
        V[r][0] = rows[r].x;
        V[r][1] = rows[r].y;
        V[r][2] = rows[r].z;
    }
    V[3][3] = 1;
    std::array<float, 16> m{};
    for (int r = 0; r < 4; ++r)
        for (int c = 0; c < 4; ++c) {
            double s = 0;
            for (int k = 0; k < 4; ++k) s += P[r][k] * V[k][c];
            m[static_cast<std::size_t>(c * 4 + r)] = static_cast<float>(s);
        }
    return m;
}

// Resolution of sub-hemicubes: half the row's, when that is still a valid resolution (even, ≥ 8).
int half_resolution(int n) { return n / 2 >= 8 && (n / 2) % 2 == 0 ? n / 2 : n; }

// One worker: a GL context current on its own thread, its item buffer and its scratch space.
class Worker {
public:
    Worker(GlContext& ctx, const Scene& scene, const ScenePieces& pieces, const HemicubeLayout& layout,
           const HemicubeOptions& opt)
        : gl_(ctx.api()), scene_(scene), pieces_(pieces), layout_(layout), half_layout_(half_resolution(layout.resolution())),
          opt_(opt) {
        const gl::Api& gl = gl_;
        // The fragment shader specialised to the piece kinds of the scene: llvmpipe runs both
        // sides of a branch under a mask, so a path no piece takes still costs every pixel.
        std::string frag(shaders::item_frag);
        const std::size_t eol = frag.find('\n') + 1;
        frag.insert(eol, fmt::format("#define HAS_TRIANGLES {}\n#define HAS_BILINEAR {}\n", pieces.has_kind[3] ? 1 : 0,
                                     pieces.has_kind[4] ? 1 : 0));
        program_ = gl::make_program(gl, "item shader", shaders::item_vert, frag);
        target_ = gl::make_item_target(gl, layout.atlas_width(), layout.atlas_height());
        half_target_ = gl::make_item_target(gl, half_layout_.atlas_width(), half_layout_.atlas_height());
        vao_ = gl::make_vertex_array(gl);
        vbo_ = gl::make_buffer(gl);
        static_vbo_ = gl::make_buffer(gl);
        grid_vbo_ = gl::make_buffer(gl);
        info_vbo_ = gl::make_buffer(gl);
        ebo_ = gl::make_buffer(gl);
        ssbo_ = gl::make_buffer(gl);
        const std::size_t slots = pieces.pos.size();
        gl.BindVertexArray(vao_.id());
        gl.BindBuffer(GL_ARRAY_BUFFER, vbo_.id());
        gl.BufferData(GL_ARRAY_BUFFER, static_cast<GLsizeiptr>(std::max<std::size_t>(slots, 1) * 3 * sizeof(float)), nullptr,
                      GL_STREAM_DRAW);
        gl.EnableVertexAttribArray(0);
        gl.VertexAttribPointer(0, 3, GL_FLOAT, GL_FALSE, 3 * sizeof(float), nullptr);
        gl.BindBuffer(GL_ARRAY_BUFFER, static_vbo_.id());
        gl.BufferData(GL_ARRAY_BUFFER, static_cast<GLsizeiptr>(pieces.param.size() * sizeof(float)), pieces.param.data(),
                      GL_STATIC_DRAW);
        gl.EnableVertexAttribArray(1);
        gl.VertexAttribPointer(1, 2, GL_FLOAT, GL_FALSE, 2 * sizeof(float), nullptr);
        gl.BindBuffer(GL_ARRAY_BUFFER, grid_vbo_.id());
        gl.BufferData(GL_ARRAY_BUFFER, static_cast<GLsizeiptr>(pieces.grid.size() * sizeof(std::uint32_t)),
                      pieces.grid.data(), GL_STATIC_DRAW);
        gl.EnableVertexAttribArray(2);
        gl.VertexAttribIPointer(2, 1, GL_UNSIGNED_INT, sizeof(std::uint32_t), nullptr);
        gl.BindBuffer(GL_ARRAY_BUFFER, info_vbo_.id());
        gl.BufferData(GL_ARRAY_BUFFER, static_cast<GLsizeiptr>(pieces.info.size() * sizeof(std::uint32_t)),
                      pieces.info.data(), GL_STATIC_DRAW);
        gl.EnableVertexAttribArray(3);
        gl.VertexAttribIPointer(3, 4, GL_UNSIGNED_INT, 4 * sizeof(std::uint32_t), nullptr);
        gl.BindBuffer(GL_ELEMENT_ARRAY_BUFFER, ebo_.id());
        gl.BindBuffer(GL_SHADER_STORAGE_BUFFER, ssbo_.id());
        gl.BufferData(GL_SHADER_STORAGE_BUFFER, static_cast<GLsizeiptr>(pieces.gpu.size() * sizeof(GpuGrid)),
                      pieces.gpu.data(), GL_STATIC_DRAW);
        gl.BindBufferBase(GL_SHADER_STORAGE_BUFFER, 0, ssbo_.id());
        gl.UseProgram(program_.id());
        u_face_ = gl.GetUniformLocation(program_.id(), "u_face");
        u_back_ = gl.GetUniformLocation(program_.id(), "u_back");
        // All state the item pass needs is set here and never changed: nothing leaks in or out.
        gl.BindFramebuffer(GL_FRAMEBUFFER, target_.fbo.id());
        gl.Enable(GL_DEPTH_TEST);
        gl.DepthFunc(GL_GREATER);
        gl.DepthMask(GL_TRUE);
        gl.ClipControl(GL_LOWER_LEFT, GL_ZERO_TO_ONE);
        gl.Disable(GL_CULL_FACE);  // back faces must block (they write kBackFace)
        gl.Disable(GL_BLEND);
        gl.Disable(GL_DITHER);
        gl.Disable(GL_MULTISAMPLE);
        gl.Disable(GL_FRAMEBUFFER_SRGB);
        gl.Disable(GL_SCISSOR_TEST);
        gl.PixelStorei(GL_PACK_ALIGNMENT, 4);
        gl::check_gl(gl, "hemicube worker setup");

        local_.resize(slots * 3);
        for (std::size_t f = 0; f < 5; ++f) {
            face_m_[f] = layout.faces()[f];
            half_face_m_[f] = half_layout_.faces()[f];
        }
        half_ids_.resize(static_cast<std::size_t>(half_layout_.atlas_width()) * half_layout_.atlas_height());
        for (auto& l : lists_) l.reserve(slots);
        all_idx_.reserve(slots * 2);
        ids_.resize(static_cast<std::size_t>(layout.atlas_width()) * layout.atlas_height());
        acc_.assign(scene.patches.size(), 0.0);
        stamp_.assign(scene.patches.size(), 0);
    }

    // Renders patch p's hemicube into ids_ (the atlas).
    void render(std::uint32_t p, HemicubeStats& st) { render(p, scene_.patches[p].centroid, false, st); }

    // Renders the hemicube of patch p from the point 'at' on it (its centroid, or a quadrature
    // point for sub-hemicubes), raised by kEyeOffset of the patch size, into the full atlas or
    // (half) the half-resolution one of sub-hemicubes.
    void render(std::uint32_t p, const Vec3& at, bool half, HemicubeStats& st) {
        const gl::Api& gl = gl_;
        const Patch& pa = scene_.patches[p];
        Stopwatch watch;
        const double angle = opt_.rotate ? hemicube_angle(opt_.seed, p) : 0.0;
        const HemicubeFrame fr = make_frame(pa.normal, angle);
        const Vec3 eye = at + pa.normal * (HemicubeRowProvider::kEyeOffset * pa.size);
        // Vertex slots (piece corners, T-vertices) relative to the eye in the local frame,
        // subtracted in double before they become floats: far-off coordinates (1e5) keep full
        // float precision near the eye. Equal world positions give bitwise equal vertices.
        const std::size_t ns = pieces_.pos.size();
        const Vec3* pos = pieces_.pos.data();
        for (std::size_t s = 0; s < ns; ++s) {
            const Vec3 d = pos[s] - eye;
            float* out = &local_[s * 3];
            out[0] = static_cast<float>(glm::dot(d, fr.tangent));
            out[1] = static_cast<float>(glm::dot(d, fr.bitangent));
            out[2] = static_cast<float>(glm::dot(d, fr.normal));
        }
        cull(st);
        st.prepare_seconds += watch.seconds();
        watch.restart();

        // Upload the corners and the five index lists back to back.
        gl.BindBuffer(GL_ARRAY_BUFFER, vbo_.id());
        gl.BufferSubData(GL_ARRAY_BUFFER, 0, static_cast<GLsizeiptr>(local_.size() * sizeof(float)), local_.data());
        all_idx_.clear();
        for (const auto& l : lists_) all_idx_.insert(all_idx_.end(), l.begin(), l.end());
        gl.BufferData(GL_ELEMENT_ARRAY_BUFFER, static_cast<GLsizeiptr>(std::max<std::size_t>(all_idx_.size(), 1) * 4),
                      all_idx_.data(), GL_STREAM_DRAW);

        gl.BindFramebuffer(GL_FRAMEBUFFER, (half ? half_target_ : target_).fbo.id());
        const std::array<FaceSpec, 5>& faces = half ? half_face_m_ : face_m_;
        const GLuint zero_id[4] = {0, 0, 0, 0};
        const GLfloat zero_depth = 0.0f;  // reversed Z: 0 is infinitely far
        gl.ClearBufferuiv(GL_COLOR, 0, zero_id);
        gl.ClearBufferfv(GL_DEPTH, 0, &zero_depth);
        const double near = HemicubeRowProvider::kNear * pa.size;
        // Front-facing pieces first, then back-facing ones pushed 64 depth units farther
        // (reversed Z: negative offset), so a two-sided plate made of two one-sided faces back to
        // back shows its front side, never the back of the other (no z-fighting; GL_GREATER also
        // lets the first drawn win exact ties; 4 units were too few for the two faces' rounding,
        // measured). No slope factor: a back face seen edge-on (a wall standing on the sender's
        // plate) has a huge depth slope, and slope × 1 let what is behind it show through
        // (test Occluders.WallSeenEdgeOnFromBothSidesBlocksEverything: 508 leaking pairs). Which side a fragment shows is the pass's (u_back,
        // from cull()'s classification of the whole piece), not gl_FrontFacing: the rasterizer
        // snaps vertices to its subpixel grid, which can turn a sliver (a triangle seen almost
        // edge-on, or a small one beside a T-vertex) over, and a front piece would then show a
        // back-face pixel.
        std::size_t first_index = 0;
        for (int pass = 0; pass < 2; ++pass) {
            if (pass == 1) {
                gl.Enable(GL_POLYGON_OFFSET_FILL);
                gl.PolygonOffset(0.0f, -64.0f);
            }
            gl.Uniform1ui(u_back_, static_cast<GLuint>(pass));
            for (int f = 0; f < 5; ++f) {
                const FaceSpec& fs = faces[static_cast<std::size_t>(f)];
                const std::size_t count = lists_[pass * 5 + f].size();
                if (count > 0) {
                    const auto m = face_matrix(fs, near);
                    gl.Viewport(fs.viewport.x, fs.viewport.y, fs.viewport.width, fs.viewport.height);
                    gl.UniformMatrix4fv(u_face_, 1, GL_FALSE, m.data());
                    gl.DrawElements(GL_TRIANGLES, static_cast<GLsizei>(count), GL_UNSIGNED_INT,
                                    reinterpret_cast<const void*>(first_index * sizeof(std::uint32_t)));
                }
                first_index += count;
            }
        }
        gl.Disable(GL_POLYGON_OFFSET_FILL);
        gl.Finish();
        st.draw_seconds += watch.seconds();
        watch.restart();
        const HemicubeLayout& lay = half ? half_layout_ : layout_;
        gl.ReadPixels(0, 0, lay.atlas_width(), lay.atlas_height(), GL_RED_INTEGER, GL_UNSIGNED_INT,
                      (half ? half_ids_ : ids_).data());
        gl::check_gl(gl, "hemicube rendering");
        st.readback_seconds += watch.seconds();
        st.hemicubes += 1;
    }

    // Row p: one hemicube at the centroid, or (sampled) the average of sub-hemicubes at the
    // patch's 2 × 2 quadrature points (geometry/quadrature.hpp, the points the near-field
    // correction's sender quadrature uses), each with its own visibility.
    void row(std::uint32_t p, SparseRow& out, HemicubeStats& st, bool sampled = false) {
        ++epoch_;
        touched_.clear();
        if (!sampled) {
            render(p, st);
            accumulate(p, 1.0, false, st);
        } else {
            const auto v = scene_.patch_vertices(p);
            patch_quadrature(std::span<const Vec3>(v.data(), scene_.patches[p].count), 2, points_, weights_);
            // At half the resolution: four of them cost about one full hemicube, and their
            // average has about the pixel noise of one (each has twice the relative noise).
            for (std::size_t q = 0; q < points_.size(); ++q) {
                render(p, points_[q], true, st);
                accumulate(p, weights_[q], true, st);
            }
            ++st.sampled_rows;
        }
        Stopwatch watch;
        std::sort(touched_.begin(), touched_.end());
        out.clear();
        out.col.reserve(touched_.size());
        out.val.reserve(touched_.size());
        for (std::uint32_t j : touched_) {
            out.col.push_back(j);
            out.val.push_back(acc_[j]);
        }
        st.accumulate_seconds += watch.seconds();
    }

    // Adds weight × ΔF of every pixel of the rendered atlas to the row being made (epoch_).
    void accumulate(std::uint32_t p, double weight, bool half, HemicubeStats& st) {
        Stopwatch watch;
        const std::vector<double>& w = (half ? half_layout_ : layout_).delta_ff();
        const std::vector<std::uint32_t>& ids = half ? half_ids_ : ids_;
        const std::uint32_t self = p + 1;
        double back = 0.0, miss = 0.0;
        const std::size_t npix = ids.size();
        for (std::size_t k = 0; k < npix; ++k) {
            const std::uint32_t id = ids[k];
            if (id == 0) {
                miss += w[k];
            } else if (id == kBackFace) {
                back += w[k];
            } else if (id == self) {
                ++st.self_hits;
            } else {
                const std::uint32_t j = id - 1;
                // An id past the last patch means a broken patch lookup (shader or pieces): a
                // clean error instead of writing past the row's arrays.
                if (j >= stamp_.size())
                    throw GlError(fmt::format("hemicube of patch {}: pixel {} shows id {}, past the last patch {}", p, k,
                                              id, stamp_.size()));
                if (stamp_[j] != epoch_) {
                    stamp_[j] = epoch_;
                    acc_[j] = 0.0;
                    touched_.push_back(j);
                }
                acc_[j] += weight * w[k];
            }
        }
        st.back_face_weight += weight * back;
        st.miss_weight += weight * miss;
        st.accumulate_seconds += watch.seconds();
    }

    const std::vector<std::uint32_t>& ids() const { return ids_; }

private:
    // Sorts the pieces into the five faces' index lists: a piece goes to a face unless all its
    // corners lie outside one of the face's frustum planes; pieces wholly behind the hemicube
    // plane (z ≤ 0: this includes the patch's own piece and every piece coplanar with it) go
    // nowhere. Corners suffice for pieces drawn with T-vertices too: those lie on the edges.
    void cull(HemicubeStats& st) {
        for (auto& l : lists_) l.clear();
        const std::size_t ng = scene_.grids.size();
        st.pieces_considered += ng;
        for (std::size_t g = 0; g < ng; ++g) {
            const std::uint32_t count = scene_.grids[g].count;
            const std::uint32_t base = pieces_.first[g];
            unsigned all = ~0u;
            bool behind = true;
            for (std::uint32_t k = 0; k < count; ++k) {
                const float* c = &local_[(base + k) * 3];
                const float x = c[0], y = c[1], z = c[2];
                behind = behind && z <= 0;
                // Outcodes against the planes x = ±z, y = ±z (top face) and y = ±x, x = ±y,
                // z = 0, z = ±x, z = ±y (side faces): a bit set for every corner means the
                // piece misses each face that has that plane.
                const bool out[13] = {x > z,  -x > z, y > z,  -y > z, z < 0,  y > x,  -y > x,
                                      y > -x, -y > -x, z > x, z > -x, z > y, z > -y};
                unsigned code = 0;
                for (unsigned b = 0; b < 13; ++b) code |= static_cast<unsigned>(out[b]) << b;
                all &= code;
            }
            if (behind) {
                ++st.pieces_behind;
                continue;
            }
            // x > y is bit 8 (-y > -x) and -x > y is bit 6 (-y > x); likewise for -y.
            constexpr unsigned kTop = 0b1111u;                                             // |x|,|y| ≤ z
            constexpr unsigned kPosX = (1u << 4) | (1u << 5) | (1u << 6) | (1u << 9);    // |y| ≤ x, 0 ≤ z ≤ x
            constexpr unsigned kNegX = (1u << 4) | (1u << 7) | (1u << 8) | (1u << 10);   // |y| ≤ -x, 0 ≤ z ≤ -x
            constexpr unsigned kPosY = (1u << 4) | (1u << 6) | (1u << 8) | (1u << 11);   // |x| ≤ y, 0 ≤ z ≤ y
            constexpr unsigned kNegY = (1u << 4) | (1u << 5) | (1u << 7) | (1u << 12);   // |x| ≤ -y, 0 ≤ z ≤ -y
            constexpr unsigned masks[5] = {kTop, kPosX, kNegX, kPosY, kNegY};
            // Front-facing: the eye (the origin) lies in front of the piece's plane, whose normal
            // (c1 − c0) × (c2 − c0) points to its front (corners CCW from the front).
            const float* c0 = &local_[base * 3];
            const float* c1 = c0 + 3;
            const float* c2 = c0 + 6;
            const double e1[3] = {double(c1[0]) - c0[0], double(c1[1]) - c0[1], double(c1[2]) - c0[2]};
            const double e2[3] = {double(c2[0]) - c0[0], double(c2[1]) - c0[1], double(c2[2]) - c0[2]};
            const double nrm[3] = {e1[1] * e2[2] - e1[2] * e2[1], e1[2] * e2[0] - e1[0] * e2[2], e1[0] * e2[1] - e1[1] * e2[0]};
            const bool back = nrm[0] * c0[0] + nrm[1] * c0[1] + nrm[2] * c0[2] > 0;
            if (back && pieces_.has_twin[g]) continue;  // its twin's front covers it (find_twins)
            const std::uint32_t* tri_begin = pieces_.tris.data() + pieces_.tri_first[g];
            const std::uint32_t* tri_end = pieces_.tris.data() + pieces_.tri_first[g + 1];
            for (std::size_t f = 0; f < 5; ++f) {
                if (all & masks[f]) {
                    ++st.pieces_culled[f];
                } else {
                    ++st.pieces_drawn[f];
                    auto& l = lists_[f + (back ? 5 : 0)];
                    if (tri_begin == tri_end) {
                        l.insert(l.end(), {base, base + 1, base + 2});
                        if (count == 4) l.insert(l.end(), {base, base + 2, base + 3});
                    } else {
                        l.insert(l.end(), tri_begin, tri_end);  // a polygon with T-vertices
                    }
                }
            }
        }
    }

    const gl::Api& gl_;
    const Scene& scene_;
    const ScenePieces& pieces_;
    const HemicubeLayout& layout_;
    const HemicubeLayout half_layout_;  // sub-hemicubes (half_resolution)
    const HemicubeOptions& opt_;
    std::array<FaceSpec, 5> face_m_, half_face_m_;
    gl::Program program_;
    gl::ItemTarget target_, half_target_;
    gl::VertexArray vao_;
    gl::Buffer vbo_, static_vbo_, grid_vbo_, info_vbo_, ebo_, ssbo_;
    GLint u_face_ = -1, u_back_ = -1;
    std::vector<float> local_;
    std::vector<std::uint32_t> lists_[10], all_idx_;  // per face: front pieces [0, 5), back [5, 10)
    std::vector<std::uint32_t> ids_, half_ids_;
    std::vector<double> acc_;
    std::vector<std::uint32_t> stamp_, touched_;
    std::uint32_t epoch_ = 0;
    std::vector<Vec3> points_;  // sub-hemicube points and weights of the current row
    std::vector<double> weights_;
};

}  // namespace

void add_stats(HemicubeStats& a, const HemicubeStats& b);

namespace {

// ---------------------------------------------------------------------------------- engines
// A worker thread computes through an Engine: either in this process on a GL context of its
// own (LocalEngine), or in a child process that owns the context (RemoteEngine).
//
// Why child processes: Mesa's llvmpipe rasterizes every context of a process through one
// screen, under one lock, so two contexts on two threads run at about 1.1× one (measured,
// docs/benchmarks.md); two processes run at 2×. Children are forked before this process has
// made any GL context and while it runs a single thread, so they inherit the scene (copy-on-
// write) and no locks or GL state; otherwise the provider falls back to threads.
class Engine {
public:
    virtual ~Engine() = default;
    virtual void start() = 0;  // on the worker thread, before the first request
    virtual void row(std::uint32_t p, SparseRow& out, HemicubeStats& st, bool sampled) = 0;
    virtual void item_buffer(std::uint32_t p, std::vector<std::uint32_t>& out) = 0;
    virtual void stop() = 0;  // on the worker thread, after the last request
};

class LocalEngine final : public Engine {
public:
    LocalEngine(std::unique_ptr<GlContext> ctx, const Scene& scene, const ScenePieces& pieces, const HemicubeLayout& layout,
                const HemicubeOptions& opt)
        : ctx_(std::move(ctx)), scene_(scene), pieces_(pieces), layout_(layout), opt_(opt) {}
    ~LocalEngine() override { ctx_.reset(); }
    void start() override {
        ctx_->make_current();
        worker_ = std::make_unique<Worker>(*ctx_, scene_, pieces_, layout_, opt_);
    }
    void row(std::uint32_t p, SparseRow& out, HemicubeStats& st, bool sampled) override {
        worker_->row(p, out, st, sampled);
    }
    void item_buffer(std::uint32_t p, std::vector<std::uint32_t>& out) override {
        HemicubeStats ignored;
        worker_->render(p, ignored);
        out = worker_->ids();
    }
    void stop() override {
        worker_.reset();
        ctx_->release_current();
    }

private:
    std::unique_ptr<GlContext> ctx_;
    const Scene& scene_;
    const ScenePieces& pieces_;
    const HemicubeLayout& layout_;
    const HemicubeOptions& opt_;
    std::unique_ptr<Worker> worker_;
};

// The wire protocol between a RemoteEngine and its child: fixed-size headers and raw arrays
// over a Unix socket pair (both ends are the same binary).
enum class Request : std::uint32_t { Row = 0, ItemBuffer = 1, SampledRow = 2 };
struct RequestMsg {
    Request kind;
    std::uint32_t patch;
};
struct ReplyMsg {
    std::uint32_t ok;      // 1: payload follows; 0: 'count' bytes of error message follow
    std::uint64_t count;   // entries (row), pixels (item buffer), bytes (hello strings, error)
    HemicubeStats stats;   // work done for this reply
};

void send_all(int fd, const void* data, std::size_t size) {
    const char* p = static_cast<const char*>(data);
    while (size > 0) {
        const ssize_t n = ::send(fd, p, size, MSG_NOSIGNAL);
        if (n < 0 && errno == EINTR) continue;
        if (n <= 0) throw GlError(fmt::format("hemicube worker pipe: send failed: {}", std::strerror(errno)));
        p += n;
        size -= static_cast<std::size_t>(n);
    }
}

// Returns false on a clean end of stream before any byte.
bool recv_all(int fd, void* data, std::size_t size) {
    char* p = static_cast<char*>(data);
    std::size_t got = 0;
    while (got < size) {
        const ssize_t n = ::recv(fd, p + got, size - got, 0);
        if (n < 0 && errno == EINTR) continue;
        if (n < 0) throw GlError(fmt::format("hemicube worker pipe: receive failed: {}", std::strerror(errno)));
        if (n == 0) {
            if (got == 0) return false;
            throw GlError("hemicube worker pipe: truncated message");
        }
        got += static_cast<std::size_t>(n);
    }
    return true;
}

template <typename T>
void send_vector(int fd, const std::vector<T>& v) {
    if (!v.empty()) send_all(fd, v.data(), v.size() * sizeof(T));
}

void send_error(int fd, const std::string& what) {
    ReplyMsg r{0, what.size(), {}};
    send_all(fd, &r, sizeof r);
    send_all(fd, what.data(), what.size());
}

[[noreturn]] void child_main(int fd, const Scene& scene, const ScenePieces& pieces, const HemicubeLayout& layout,
                             const HemicubeOptions& opt) {
    int code = 0;
    try {
        std::unique_ptr<GlContext> ctx = create_headless_context(opt.backend);
        ctx->make_current();
        Worker worker(*ctx, scene, pieces, layout, opt);
        const std::string hello = ctx->backend() + '\n' + ctx->renderer();
        ReplyMsg h{1, hello.size(), {}};
        send_all(fd, &h, sizeof h);
        send_all(fd, hello.data(), hello.size());
        SparseRow row;
        RequestMsg req{};
        while (recv_all(fd, &req, sizeof req)) {
            try {
                ReplyMsg r{1, 0, {}};
                if (req.kind == Request::Row || req.kind == Request::SampledRow) {
                    worker.row(req.patch, row, r.stats, req.kind == Request::SampledRow);
                    r.count = row.nnz();
                    send_all(fd, &r, sizeof r);
                    send_vector(fd, row.col);
                    send_vector(fd, row.val);
                } else {
                    worker.render(req.patch, r.stats);
                    r.stats = HemicubeStats{};
                    r.count = worker.ids().size();
                    send_all(fd, &r, sizeof r);
                    send_vector(fd, worker.ids());
                }
            } catch (const std::exception& e) {
                send_error(fd, e.what());
            }
        }
        ctx->release_current();
    } catch (const std::exception& e) {
        try {
            send_error(fd, e.what());
        } catch (...) {
        }
        code = 1;
    }
    // No destructors of the parent's objects, no atexit handlers, no flush of inherited stdio.
    std::_Exit(code);
}

class RemoteEngine final : public Engine {
public:
    // Forks the child; call only while this process has one thread and no GL context.
    RemoteEngine(const Scene& scene, const ScenePieces& pieces, const HemicubeLayout& layout, const HemicubeOptions& opt) {
        int sv[2];
        if (::socketpair(AF_UNIX, SOCK_STREAM | SOCK_CLOEXEC, 0, sv) != 0)
            throw GlError(fmt::format("socketpair for a hemicube worker failed: {}", std::strerror(errno)));
        std::fflush(nullptr);
        pid_ = ::fork();
        if (pid_ < 0) {
            ::close(sv[0]);
            ::close(sv[1]);
            throw GlError(fmt::format("fork of a hemicube worker failed: {}", std::strerror(errno)));
        }
        if (pid_ == 0) {
            // Keep only stdio and this child's socket (as fd 3): the parent's ends of earlier
            // siblings' sockets must not stay open here, or those siblings never see the end of
            // their requests.
            int fd = sv[1];
            if (fd != 3) {
                ::dup2(fd, 3);
                fd = 3;
            }
            ::close_range(4, ~0u, 0);
            setenv("LP_NUM_THREADS", "0", 0);
            child_main(fd, scene, pieces, layout, opt);
        }
        ::close(sv[1]);
        fd_ = sv[0];
    }
    ~RemoteEngine() override {
        if (fd_ >= 0) ::close(fd_);  // the child sees the end of its requests and exits
        if (pid_ > 0) {
            int status = 0;
            while (::waitpid(pid_, &status, 0) < 0 && errno == EINTR) {
            }
        }
    }
    // Reads the child's hello: its backend and GL_RENDERER, or why it could not start.
    std::pair<std::string, std::string> hello() {
        const std::string text = read_reply_text();
        const auto nl = text.find('\n');
        return {text.substr(0, nl), nl == std::string::npos ? std::string() : text.substr(nl + 1)};
    }
    void start() override {}
    void stop() override {}
    void row(std::uint32_t p, SparseRow& out, HemicubeStats& st, bool sampled) override {
        const ReplyMsg r = request(sampled ? Request::SampledRow : Request::Row, p);
        out.col.resize(r.count);
        out.val.resize(r.count);
        if (r.count) {
            recv_or_throw(out.col.data(), r.count * sizeof(std::uint32_t));
            recv_or_throw(out.val.data(), r.count * sizeof(double));
        }
        add_stats(st, r.stats);
    }
    void item_buffer(std::uint32_t p, std::vector<std::uint32_t>& out) override {
        const ReplyMsg r = request(Request::ItemBuffer, p);
        out.resize(r.count);
        if (r.count) recv_or_throw(out.data(), r.count * sizeof(std::uint32_t));
    }

private:
    ReplyMsg request(Request kind, std::uint32_t p) {
        const RequestMsg req{kind, p};
        send_all(fd_, &req, sizeof req);
        ReplyMsg r{};
        recv_or_throw(&r, sizeof r);
        if (!r.ok) throw GlError(read_text(r.count));
        return r;
    }
    std::string read_reply_text() {
        ReplyMsg r{};
        recv_or_throw(&r, sizeof r);
        std::string text = read_text(r.count);
        if (!r.ok) throw GlError(text);
        return text;
    }
    std::string read_text(std::uint64_t n) {
        std::string text(n, '\0');
        if (n) recv_or_throw(text.data(), n);
        return text;
    }
    void recv_or_throw(void* data, std::size_t size) {
        if (!recv_all(fd_, data, size)) {
            int status = 0;
            std::string how = "exited";
            if (::waitpid(pid_, &status, 0) == pid_) {
                how = WIFSIGNALED(status) ? fmt::format("was killed by signal {}", WTERMSIG(status))
                                          : fmt::format("exited with status {}", WEXITSTATUS(status));
                pid_ = -1;
            }
            throw GlError("a hemicube worker process " + how + " unexpectedly");
        }
    }
    static void add_stats(HemicubeStats& a, const HemicubeStats& b) { ::ffcube::add_stats(a, b); }

    int fd_ = -1;
    pid_t pid_ = -1;
};

// True when fork() is safe here: this process runs a single thread (no lock can be held by a
// thread the child would not have) and has never made a GL context (no driver state to share).
bool can_fork_workers() {
    if (gl::context_created_in_process()) return false;
    std::ifstream status("/proc/self/status");
    std::string line;
    while (std::getline(status, line))
        if (line.rfind("Threads:", 0) == 0) return std::stoi(line.substr(8)) == 1;
    return false;
}

}  // namespace

// Workers live as long as the provider: each owns a thread, and on it a GL context and a Worker.
// compute_rows hands out row positions through a counter; finished rows wait in a window of
// slots until the calling thread passes them to the sink in list order, so the output does not
// depend on which worker computed what, and memory stays bounded.
struct HemicubeRowProvider::Impl {
    const Scene& scene;
    HemicubeOptions opt;
    HemicubeLayout layout;
    ScenePieces pieces;
    std::string backend, renderer;
    std::vector<std::unique_ptr<Engine>> engines;
    std::vector<std::thread> threads;
    bool processes = false;

    std::mutex mutex;
    std::condition_variable cv_work, cv_done;
    bool stopping = false;
    std::uint64_t generation = 0;  // bumped for each compute_rows call
    std::span<const std::uint32_t> rows;
    const RowProvider::SampleQuery* query = nullptr;  // compute_rows_sampled's, during that call
    std::size_t next = 0, consumed = 0, window = 0;
    std::vector<SparseRow> slots;
    std::vector<char> ready;
    std::exception_ptr error;
    unsigned started = 0;
    HemicubeStats stats;
    // item_buffer() requests are served by worker 0.
    std::uint32_t item_request = 0;
    bool item_pending = false;
    std::vector<std::uint32_t> item_result;

    std::size_t in_flight = 0;

    Impl(const Scene& s, const HemicubeOptions& o) : scene(s), opt(o), layout(o.resolution), pieces(prepare_pieces(s)) {}
    ~Impl() {
        {
            std::lock_guard lock(mutex);
            stopping = true;
        }
        cv_work.notify_all();
        for (auto& t : threads) t.join();
        // Engines (contexts, child processes) go after their threads have stopped.
    }

    void worker_main(unsigned index) {
        Engine& w = *engines[index];
        try {
            w.start();
        } catch (...) {
            std::lock_guard lock(mutex);
            if (!error) error = std::current_exception();
            ++started;
            cv_done.notify_all();
            return;
        }
        {
            std::lock_guard lock(mutex);
            ++started;
            cv_done.notify_all();
        }
        HemicubeStats local;
        SparseRow row;
        std::unique_lock lock(mutex);
        for (;;) {
            cv_work.wait(lock, [&] {
                return stopping || (index == 0 && item_pending) ||
                       (next < rows.size() && next < consumed + window && !error);
            });
            if (stopping) break;
            if (index == 0 && item_pending) {
                const std::uint32_t p = item_request;
                lock.unlock();
                std::vector<std::uint32_t> result;
                try {
                    w.item_buffer(p, result);
                } catch (...) {
                    lock.lock();
                    if (!error) error = std::current_exception();
                    item_pending = false;
                    cv_done.notify_all();
                    continue;
                }
                lock.lock();
                item_result = std::move(result);
                item_pending = false;
                cv_done.notify_all();
                continue;
            }
            const std::size_t k = next++;
            const std::uint32_t i = rows[k];
            const RowProvider::SampleQuery* const ask = query;
            ++in_flight;
            lock.unlock();
            try {
                // The caller's query runs here, on this worker thread (it is thread-safe).
                using RowPlan = RowProvider::RowPlan;
                const RowPlan plan = ask ? (*ask)(k) : RowPlan::centre;
                if (plan == RowPlan::skip) {
                    row.clear();
                    ++local.skipped_rows;
                } else {
                    w.row(i, row, local, plan == RowPlan::sampled);
                }
            } catch (...) {
                lock.lock();
                if (!error) error = std::current_exception();
                --in_flight;
                cv_done.notify_all();
                continue;
            }
            lock.lock();
            std::swap(slots[k % window], row);
            ready[k % window] = 1;
            merge(stats, local);
            local = HemicubeStats{};
            --in_flight;
            cv_done.notify_all();
        }
        lock.unlock();
        w.stop();
    }

    static void merge(HemicubeStats& a, const HemicubeStats& b) { add_stats(a, b); }
};

void add_stats(HemicubeStats& a, const HemicubeStats& b) {
    a.hemicubes += b.hemicubes;
    a.prepare_seconds += b.prepare_seconds;
    a.draw_seconds += b.draw_seconds;
    a.readback_seconds += b.readback_seconds;
    a.accumulate_seconds += b.accumulate_seconds;
    a.sampled_rows += b.sampled_rows;
    a.skipped_rows += b.skipped_rows;
    a.pieces_considered += b.pieces_considered;
    a.pieces_behind += b.pieces_behind;
    for (std::size_t f = 0; f < 5; ++f) {
        a.pieces_drawn[f] += b.pieces_drawn[f];
        a.pieces_culled[f] += b.pieces_culled[f];
    }
    a.back_face_weight += b.back_face_weight;
    a.miss_weight += b.miss_weight;
    a.self_hits += b.self_hits;
}


HemicubeRowProvider::HemicubeRowProvider(const Scene& scene, const HemicubeOptions& options) {
    if (options.resolution < 8 || options.resolution > 8192 || options.resolution % 2 != 0)
        throw InputError(fmt::format("--resolution {}: must be an even number of pixels from 8 to 8192", options.resolution));
    if (scene.patches.size() >= kBackFace - 1) throw InputError("the scene has too many patches for 32-bit item IDs");
    unsigned n = options.threads ? options.threads : std::max(1u, std::thread::hardware_concurrency());
    n = static_cast<unsigned>(std::min<std::size_t>(n, std::max<std::size_t>(1, scene.patches.size())));
    impl_ = std::make_unique<Impl>(scene, options);
    Impl& im = *impl_;
    im.opt.threads = n;
    // llvmpipe starts rasterizer threads (one per core) for every context unless told otherwise;
    // K workers would then run K × cores threads that fight over the cores. With one rasterizing
    // thread per context, --threads K uses K cores, and scaling is the workers' (measured in
    // docs/benchmarks.md). A user's own LP_NUM_THREADS is respected. Must precede the first
    // context: llvmpipe reads it when its screen is created.
    setenv("LP_NUM_THREADS", "0", /*overwrite=*/0);
    if (can_fork_workers()) {
        im.processes = true;
        for (unsigned t = 0; t < n; ++t) {
            auto remote = std::make_unique<RemoteEngine>(im.scene, im.pieces, im.layout, im.opt);
            RemoteEngine& r = *remote;
            im.engines.push_back(std::move(remote));
            std::tie(im.backend, im.renderer) = r.hello();  // throws why the child could not start
        }
    } else {
        std::unique_ptr<GlContext> first = create_headless_context(options.backend);
        im.backend = first->backend();
        im.renderer = first->renderer();
        std::vector<std::unique_ptr<GlContext>> contexts;
        for (unsigned t = 1; t < n; ++t) contexts.push_back(first->create_sibling());
        im.engines.push_back(std::make_unique<LocalEngine>(std::move(first), im.scene, im.pieces, im.layout, im.opt));
        for (auto& c : contexts)
            im.engines.push_back(std::make_unique<LocalEngine>(std::move(c), im.scene, im.pieces, im.layout, im.opt));
    }
    for (unsigned t = 0; t < n; ++t) im.threads.emplace_back([&im, t] { im.worker_main(t); });
    std::unique_lock lock(im.mutex);
    im.cv_done.wait(lock, [&] { return im.started == n; });
    if (im.error) {
        std::exception_ptr e = im.error;
        lock.unlock();
        impl_.reset();  // joins the threads that did start
        std::rethrow_exception(e);
    }
}

HemicubeRowProvider::~HemicubeRowProvider() = default;

std::uint32_t HemicubeRowProvider::size() const { return static_cast<std::uint32_t>(impl_->scene.patches.size()); }

void HemicubeRowProvider::compute_rows(std::span<const std::uint32_t> rows, const RowSink& sink) {
    Impl& im = *impl_;
    for (std::uint32_t i : rows) FFCUBE_CHECK_MSG(i < size(), "row index out of range");
    if (rows.empty()) return;
    std::unique_lock lock(im.mutex);
    if (im.error) std::rethrow_exception(im.error);
    im.rows = rows;
    im.next = 0;
    im.consumed = 0;
    im.window = 4 * im.threads.size();
    im.slots.resize(im.window);
    im.ready.assign(im.window, 0);
    im.cv_work.notify_all();
    // However this call ends (done, a worker failed, the sink threw), no worker may still be
    // reading 'rows' or writing a slot when it returns.
    auto finish = [&] {
        im.next = im.rows.size();
        im.cv_done.wait(lock, [&] { return im.in_flight == 0; });
        im.rows = {};
    };
    SparseRow current;
    try {
        for (std::size_t k = 0; k < rows.size(); ++k) {
            im.cv_done.wait(lock, [&] { return im.ready[k % im.window] || im.error; });
            if (im.error) std::rethrow_exception(im.error);
            std::swap(current, im.slots[k % im.window]);
            im.ready[k % im.window] = 0;
            ++im.consumed;
            im.cv_work.notify_all();
            lock.unlock();
            sink(rows[k], current);
            lock.lock();
        }
    } catch (...) {
        if (!lock.owns_lock()) lock.lock();
        finish();
        throw;
    }
    finish();
}

void HemicubeRowProvider::compute_rows_sampled(std::span<const std::uint32_t> rows, const SampleQuery& sampled,
                                               const RowSink& sink) {
    Impl& im = *impl_;
    {
        std::lock_guard lock(im.mutex);
        im.query = &sampled;
    }
    // compute_rows returns only when no worker is still on a row of this call.
    struct Reset {
        Impl& im;
        ~Reset() {
            std::lock_guard lock(im.mutex);
            im.query = nullptr;
        }
    } reset{im};
    compute_rows(rows, sink);
}

std::vector<std::uint32_t> HemicubeRowProvider::item_buffer(std::uint32_t i) {
    Impl& im = *impl_;
    FFCUBE_CHECK_MSG(i < size(), "patch index out of range");
    std::unique_lock lock(im.mutex);
    if (im.error) std::rethrow_exception(im.error);
    im.item_request = i;
    im.item_pending = true;
    im.cv_work.notify_all();
    im.cv_done.wait(lock, [&] { return !im.item_pending; });
    if (im.error) std::rethrow_exception(im.error);
    return std::move(im.item_result);
}

HemicubeStats HemicubeRowProvider::stats() const {
    std::lock_guard lock(impl_->mutex);
    return impl_->stats;
}
std::string HemicubeRowProvider::backend() const { return impl_->backend; }
std::string HemicubeRowProvider::renderer() const { return impl_->renderer; }
unsigned HemicubeRowProvider::threads() const { return static_cast<unsigned>(impl_->threads.size()); }
std::string HemicubeRowProvider::workers() const { return impl_->processes ? "processes" : "threads"; }
int HemicubeRowProvider::resolution() const { return impl_->layout.resolution(); }

}  // namespace ffcube
