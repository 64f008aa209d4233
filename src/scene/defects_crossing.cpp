// Faces that pass through each other (refused), the defect checks in order, and the recentring
// of a model far from its origin (include/ffcube/scene/defects.hpp; docs/robustness.md).
#include <fmt/format.h>
#include <glm/common.hpp>
#include <glm/geometric.hpp>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <limits>
#include <set>

#include "ear_clip.hpp"
#include "ffcube/core/error.hpp"
#include "ffcube/geometry/tolerance.hpp"
#include "ffcube/scene/defects.hpp"

namespace ffcube {

namespace {

constexpr std::size_t kNamed = 3;

struct Tri {
    std::array<Vec3, 3> p;
    Vec3 n;             // unit normal
    Vec3 lo, hi;        // box
    double tol = 0;     // "on this triangle's plane": planarity tolerance of its face
    std::uint32_t face = 0;
};

// The face's triangles: as the mesher makes them (a triangle; a convex planar polygon as a fan,
// any other by ear clipping in the Newell plane). A fan from vertex 0 covers a convex polygon
// exactly; the crossing test does not depend on which diagonals are used inside a planar face.
void triangles_of(const ObjModel& m, std::uint32_t fi, std::vector<Vec3>& poly, std::vector<std::array<Vec3, 3>>& out,
                  double coord_max, std::vector<Tri>& tris) {
    poly.clear();
    for (const std::uint32_t v : m.faces[fi].v)
        if (poly.empty() || m.positions[v] != poly.back()) poly.push_back(m.positions[v]);
    while (poly.size() > 1 && poly.back() == poly.front()) poly.pop_back();
    if (poly.size() < 3) return;
    const double size = polygon_max_edge(poly);
    const double area = polygon_area(poly);
    if (!(area > 1e-12 * size * size)) return;  // degenerate: the mesher drops it
    out.clear();
    if (poly.size() == 3) {
        out.push_back({poly[0], poly[1], poly[2]});
    } else {
        detail::ear_clip(poly, polygon_normal(poly), out);
    }
    // A vertex within 1e-6 of the face's size of a plane counts as on it: faces off their plane
    // by up to that much are kept whole by the mesher (kPlanarityTolerance), and the rounding of
    // the coordinates (16 ulps of the largest) is below it for any scene recentred at loading.
    const double tol = geometric_tolerance(kPlanarityTolerance, size, coord_max);
    for (const auto& t : out) {
        const Vec3 c = glm::cross(t[1] - t[0], t[2] - t[0]);
        const double l = glm::length(c);
        if (!(l > 1e-12 * size * size)) continue;
        Tri tri{t, c / l, glm::min(t[0], glm::min(t[1], t[2])), glm::max(t[0], glm::max(t[1], t[2])), tol, fi};
        tris.push_back(tri);
    }
}

// The cut of triangle a by b's plane, as an interval along `dir`, when a has vertices strictly on
// both sides of that plane (beyond b.tol); false otherwise (a touches the plane or misses it).
bool cut_interval(const Tri& a, const Tri& b, const Vec3& dir, double& t0, double& t1) {
    std::array<double, 3> d{};
    bool pos = false, neg = false;
    for (int k = 0; k < 3; ++k) {
        d[k] = glm::dot(a.p[k] - b.p[0], b.n);
        if (std::abs(d[k]) <= b.tol) d[k] = 0;
        pos = pos || d[k] > 0;
        neg = neg || d[k] < 0;
    }
    if (!(pos && neg)) return false;
    t0 = INFINITY, t1 = -INFINITY;
    for (int k = 0; k < 3; ++k) {
        const int l = (k + 1) % 3;
        Vec3 x;
        bool any = false;
        if (d[k] == 0) x = a.p[k], any = true;
        if (d[k] * d[l] < 0) {
            const Vec3 y = a.p[k] + (a.p[l] - a.p[k]) * (d[k] / (d[k] - d[l]));
            const double s = glm::dot(y, dir);
            t0 = std::min(t0, s), t1 = std::max(t1, s);
        }
        if (any) {
            const double s = glm::dot(x, dir);
            t0 = std::min(t0, s), t1 = std::max(t1, s);
        }
    }
    return t0 <= t1;
}

// The length of the segment along which a and b pass through each other; 0 when they do not.
double crossing_length(const Tri& a, const Tri& b) {
    const Vec3 c = glm::cross(a.n, b.n);
    const double s = glm::length(c);
    if (!(s > 1e-12)) return 0;  // parallel planes: coplanar contact or apart
    const Vec3 dir = c / s;
    double a0, a1, b0, b1;
    if (!cut_interval(a, b, dir, a0, a1) || !cut_interval(b, a, dir, b0, b1)) return 0;
    const double overlap = std::min(a1, b1) - std::max(a0, b0);
    // Both cuts run through the interiors of their triangles; where they overlap by more than
    // the plane tolerance, points interior to both faces lie on both: the faces cross.
    return overlap > std::max(a.tol, b.tol) ? overlap : 0;
}

}  // namespace

std::size_t refuse_crossing_faces(const ObjModel& model) {
    std::vector<Tri> tris;
    {
        Vec3 lo(INFINITY), hi(-INFINITY);
        for (const Vec3& p : model.positions) lo = glm::min(lo, p), hi = glm::max(hi, p);
        double coord_max = 0;
        for (int k = 0; k < 3 && !model.positions.empty(); ++k) coord_max = std::max({coord_max, std::abs(lo[k]), std::abs(hi[k])});
        std::vector<Vec3> poly;
        std::vector<std::array<Vec3, 3>> out;
        tris.reserve(model.faces.size());
        for (std::uint32_t fi = 0; fi < model.faces.size(); ++fi) triangles_of(model, fi, poly, out, coord_max, tris);
    }
    const std::size_t n = tris.size();
    if (n < 2) return 0;
    // A uniform grid of about n cells over the triangles' box (each side at least 1e-3 of the
    // largest, so a flat scene gets a flat grid), each triangle in every cell its box (grown by
    // its tolerance) meets; a pair is tested once, in the cell holding the low corner of the
    // intersection of their boxes.
    Vec3 lo(INFINITY), hi(-INFINITY);
    for (Tri& t : tris) {
        t.lo -= Vec3(t.tol), t.hi += Vec3(t.tol);
        lo = glm::min(lo, t.lo), hi = glm::max(hi, t.hi);
    }
    const double widest = std::max({hi.x - lo.x, hi.y - lo.y, hi.z - lo.z});
    const Vec3 ext = glm::max(hi - lo, Vec3(std::max(1e-3 * widest, 1e-300)));
    const double h = std::cbrt(ext.x * ext.y * ext.z / static_cast<double>(n));
    std::array<std::int64_t, 3> dims{};
    for (int k = 0; k < 3; ++k) dims[k] = std::clamp<std::int64_t>(static_cast<std::int64_t>(ext[k] / h), 1, 1024);
    const auto cell = [&](const Vec3& p, int k) {
        return std::clamp<std::int64_t>(static_cast<std::int64_t>((p[k] - lo[k]) / ext[k] * static_cast<double>(dims[k])), 0,
                                        dims[k] - 1);
    };
    const auto id = [&](std::int64_t x, std::int64_t y, std::int64_t z) { return static_cast<std::size_t>((z * dims[1] + y) * dims[0] + x); };
    const auto each_cell = [&](const Tri& t, auto&& f) {
        const std::int64_t x0 = cell(t.lo, 0), x1 = cell(t.hi, 0), y0 = cell(t.lo, 1), y1 = cell(t.hi, 1), z0 = cell(t.lo, 2),
                           z1 = cell(t.hi, 2);
        for (std::int64_t z = z0; z <= z1; ++z)
            for (std::int64_t y = y0; y <= y1; ++y)
                for (std::int64_t x = x0; x <= x1; ++x) f(id(x, y, z));
    };
    // Memory stays proportional to the triangles: at most 8 n + 4096 cells, and at most 32 n + 2^20
    // (triangle, cell) entries, the grid made coarser (its largest side halved) until both hold
    // (large triangles over a fine grid would otherwise enter many cells each).
    const auto largest = [&] { return static_cast<int>(std::max_element(dims.begin(), dims.end()) - dims.begin()); };
    std::size_t cells = 0;
    std::vector<std::size_t> start;
    for (;;) {
        cells = static_cast<std::size_t>(dims[0] * dims[1] * dims[2]);
        if (cells > 8 * n + 4096) {
            dims[largest()] = std::max<std::int64_t>(1, dims[largest()] / 2);
            continue;
        }
        std::size_t entries = 0;
        for (const Tri& t : tris)
            entries += static_cast<std::size_t>((cell(t.hi, 0) - cell(t.lo, 0) + 1) * (cell(t.hi, 1) - cell(t.lo, 1) + 1) *
                                                (cell(t.hi, 2) - cell(t.lo, 2) + 1));
        if (entries > 32 * n + (std::size_t{1} << 20) && cells > 1) {
            dims[largest()] = std::max<std::int64_t>(1, dims[largest()] / 2);
            continue;
        }
        break;
    }
    start.assign(cells + 1, 0);
    for (const Tri& t : tris) each_cell(t, [&](std::size_t c) { ++start[c + 1]; });
    for (std::size_t c = 0; c < cells; ++c) start[c + 1] += start[c];
    std::vector<std::uint32_t> items(start[cells]);
    {
        std::vector<std::size_t> fill(start.begin(), start.end() - 1);
        for (std::uint32_t i = 0; i < n; ++i) each_cell(tris[i], [&](std::size_t c) { items[fill[c]++] = i; });
    }
    // The first face pairs found, with the length along which their triangles cross (summed:
    // each point of a crossing lies in one triangle of each face, but on their diagonals).
    struct Named {
        std::pair<std::uint32_t, std::uint32_t> faces;
        double length = 0;
    };
    std::vector<Named> named;
    std::set<std::pair<std::uint32_t, std::uint32_t>> crossing;  // every face pair found
    // Enough to refuse: counting stops at kMaxCounted pairs (a soup of large random triangles has
    // nearly every pair crossing), so the message says "at least".
    constexpr std::size_t kMaxCounted = 1000;
    for (std::size_t c = 0; c < cells && crossing.size() < kMaxCounted; ++c)
        for (std::size_t a = start[c]; a < start[c + 1]; ++a)
            for (std::size_t b = a + 1; b < start[c + 1]; ++b) {
                const Tri& s = tris[items[a]];
                const Tri& t = tris[items[b]];
                if (s.face == t.face) continue;
                const Vec3 ilo = glm::max(s.lo, t.lo), ihi = glm::min(s.hi, t.hi);
                if (ilo.x > ihi.x || ilo.y > ihi.y || ilo.z > ihi.z) continue;
                if (id(cell(ilo, 0), cell(ilo, 1), cell(ilo, 2)) != c) continue;  // tested in another cell
                const double len = crossing_length(s, t);
                if (!(len > 0)) continue;
                const std::pair<std::uint32_t, std::uint32_t> faces{std::min(s.face, t.face), std::max(s.face, t.face)};
                crossing.insert(faces);
                const auto it = std::find_if(named.begin(), named.end(), [&](const Named& x) { return x.faces == faces; });
                if (it != named.end())
                    it->length += len;
                else if (named.size() < kNamed)
                    named.push_back({faces, len});
            }
    const std::size_t pairs = crossing.size();
    if (pairs == 0) return 0;
    // Cells are visited in a fixed order, so the pairs named are the same on every run.
    std::sort(named.begin(), named.end(), [](const Named& x, const Named& y) { return x.faces < y.faces; });
    std::string list;
    for (const Named& nm : named) {
        const auto name = [&](std::uint32_t i) {
            return fmt::format("{} (object '{}')", face_place(model, i), model.objects[model.faces[i].object]);
        };
        list += fmt::format("{}{} and {} (along {:.3g})", list.empty() ? "" : "; ", name(nm.faces.first),
                            name(nm.faces.second), nm.length);
    }
    throw InputError(fmt::format(
        "{}: {}{} pair{} of faces pass through each other: {}{}; part of each lies inside what the "
        "other bounds, where no light can be, so no form factor of the whole face is right: cut the faces along their "
        "intersection and remove the buried parts, or move them apart",
        model.source, pairs >= kMaxCounted ? "at least " : "", pairs, pairs == 1 ? "" : "s", list,
        pairs > named.size() ? ", ..." : ""));
}

DefectStats check_defects(ObjModel& model) {
    refuse_self_intersecting_faces(model);
    DefectStats st = remove_duplicate_faces(model);
    st.crossing_pairs = refuse_crossing_faces(model);
    return st;
}

Vec3 recentre(ObjModel& model) {
    if (model.positions.empty()) return Vec3(0.0);
    Vec3 lo(INFINITY), hi(-INFINITY);
    for (const Vec3& p : model.positions) lo = glm::min(lo, p), hi = glm::max(hi, p);
    const double diagonal = glm::length(hi - lo);
    Vec3 origin(0.0);
    for (int k = 0; k < 3; ++k) {
        // Only an axis along which the scene lies far from 0: there every coordinate is within a
        // factor (1 + 1/1023) of the centre's, so x − centre is exact (Sterbenz's lemma) and the
        // geometry keeps every bit; near 0 nothing is moved (the rows stay the same bytes).
        const double c = 0.5 * (lo[k] + hi[k]);
        if (std::max(std::abs(lo[k]), std::abs(hi[k])) > kRecentreRatio * diagonal) origin[k] = c;
    }
    if (origin == Vec3(0.0)) return origin;
    for (Vec3& p : model.positions) p -= origin;
    return origin;
}

}  // namespace ffcube
