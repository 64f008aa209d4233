// Defects found after loading and before meshing: bow-tie polygons, duplicate faces, faces that
// pass through each other, and the recentring of a model far from the origin
// (docs/robustness.md, "Defective geometry" and "Far from the origin").
#include "ffcube/scene/defects.hpp"

#include <fmt/format.h>
#include <glm/common.hpp>
#include <glm/geometric.hpp>
#include <glm/vec2.hpp>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <limits>
#include <unordered_map>
#include <utility>

#include "ear_clip.hpp"
#include "ffcube/core/error.hpp"
#include "ffcube/geometry/tolerance.hpp"

namespace ffcube {

namespace {

// How many defects a message or warning names one by one (the count covers the rest).
constexpr std::size_t kNamed = 3;

// SplitMix64's finaliser: a hash whose every output bit depends on every input bit.
std::uint64_t mix(std::uint64_t z) {
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
    return z ^ (z >> 31);
}

// The face's vertices with consecutive repeats dropped (as the mesher drops them).
void face_polygon(const ObjModel& m, const ObjFace& f, std::vector<Vec3>& poly) {
    poly.clear();
    for (const std::uint32_t v : f.v)
        if (poly.empty() || m.positions[v] != poly.back()) poly.push_back(m.positions[v]);
    while (poly.size() > 1 && poly.back() == poly.front()) poly.pop_back();
}

std::string named(const ObjModel& m, std::size_t face) {
    const ObjFace& f = m.faces[face];
    const std::string object = f.object < m.objects.size() ? m.objects[f.object] : std::string("?");
    return fmt::format("{} (object '{}')", face_place(m, face), object);
}

struct Bounds {
    Vec3 lo{INFINITY}, hi{-INFINITY};
    double coord_max = 0;
};

Bounds bounds_of(const ObjModel& m) {
    Bounds b;
    for (const ObjFace& f : m.faces)
        for (const std::uint32_t v : f.v) {
            const Vec3& p = m.positions[v];
            b.lo = glm::min(b.lo, p);
            b.hi = glm::max(b.hi, p);
        }
    if (!(b.lo.x <= b.hi.x)) b.lo = b.hi = Vec3(0.0);
    b.coord_max = std::max({std::abs(b.lo.x), std::abs(b.lo.y), std::abs(b.lo.z), std::abs(b.hi.x), std::abs(b.hi.y),
                            std::abs(b.hi.z)});
    return b;
}

// Proper crossing of segments ab and cd in the plane: each pair of ends strictly on both sides
// of the other segment's line, by more than tol (an area: rounding of the orientation test).
bool segments_cross(const glm::dvec2& a, const glm::dvec2& b, const glm::dvec2& c, const glm::dvec2& d, double tol) {
    const auto orient = [](const glm::dvec2& p, const glm::dvec2& q, const glm::dvec2& r) {
        return (q.x - p.x) * (r.y - p.y) - (q.y - p.y) * (r.x - p.x);
    };
    const double o1 = orient(a, b, c), o2 = orient(a, b, d), o3 = orient(c, d, a), o4 = orient(c, d, b);
    return ((o1 > tol && o2 < -tol) || (o1 < -tol && o2 > tol)) && ((o3 > tol && o4 < -tol) || (o3 < -tol && o4 > tol));
}

}  // namespace

std::string face_place(const ObjModel& model, std::size_t face) {
    const std::uint32_t line = model.faces[face].line;
    if (model.faces_numbered) return fmt::format("{}: facet {}", model.source, line);
    if (line == 0) return fmt::format("{}: face {}", model.source, face + 1);
    return fmt::format("{}:{}", model.source, line);
}

double coincidence_tolerance(const ObjModel& model) {
    const Bounds b = bounds_of(model);
    // 1e-9 of the scene's size: far below any feature a form factor resolves (the mesher drops
    // faces of area below 1e-12 × edge²), far above the rounding of coordinates written with 9 or
    // more significant digits relative to the scene; and never below 16 ulps of the largest
    // coordinate, the precision the stored coordinates have (geometry/tolerance.hpp).
    return geometric_tolerance(1e-9, glm::length(b.hi - b.lo), b.coord_max);
}

void refuse_self_intersecting_faces(const ObjModel& model) {
    std::vector<Vec3> poly;
    std::vector<glm::dvec2> q;
    for (std::size_t fi = 0; fi < model.faces.size(); ++fi) {
        face_polygon(model, model.faces[fi], poly);
        const std::size_t n = poly.size();
        if (n < 4) continue;  // a triangle cannot cross itself
        const double size = polygon_max_edge(poly);
        if (!(size > 0)) continue;
        // The Newell normal, or, where the lobes' areas cancel (a symmetric bow-tie has none, and
        // the mesher would drop it as degenerate, silently), the largest corner's.
        Vec3 normal(0.0);
        if (polygon_area(poly) > 1e-12 * size * size) {
            normal = polygon_normal(poly);
        } else {
            double best = 0;
            for (std::size_t k = 1; k + 1 < n; ++k) {
                const Vec3 c = glm::cross(poly[k] - poly[0], poly[k + 1] - poly[0]);
                if (glm::length(c) > best) best = glm::length(c), normal = c / best;
            }
            if (!(best > 1e-12 * size * size)) continue;  // collinear: the mesher drops it
        }
        Vec3 t, b;
        orthonormal_basis(normal, t, b);
        q.resize(n);
        for (std::size_t k = 0; k < n; ++k) q[k] = {glm::dot(poly[k] - poly[0], t), glm::dot(poly[k] - poly[0], b)};
        // Orientations are areas of size²; 1e-12 × size² is the mesher's "no area" (kDegenerate):
        // edges that only touch, or cross by less than that, are not a bow-tie.
        const double tol = 1e-12 * size * size;
        // O(n²) edge pairs: faces of a few hundred vertices (a disk) cost microseconds; beyond
        // 4096 vertices the check is skipped (the mesher's ear clipping still gives triangles).
        if (n > 4096) continue;
        for (std::size_t e = 0; e < n; ++e)
            for (std::size_t g = e + 2; g < n; ++g) {
                if (e == 0 && g == n - 1) continue;  // adjacent through the closing edge
                if (segments_cross(q[e], q[(e + 1) % n], q[g], q[(g + 1) % n], tol))
                    throw InputError(fmt::format(
                        "{}: this face of {} vertices crosses itself (its edges {}-{} and {}-{} cross: a bow-tie), in object "
                        "'{}'; its two loops would face opposite ways, so ffcube cannot tell which surface was meant: split it "
                        "into simple polygons",
                        face_place(model, fi), n, e + 1, (e + 1) % n + 1, g + 1, (g + 1) % n + 1,
                        model.objects[model.faces[fi].object]));
            }
    }
}

DefectStats remove_duplicate_faces(ObjModel& model) {
    DefectStats st;
    st.tolerance = coincidence_tolerance(model);
    const double tol = st.tolerance;
    if (model.faces.empty()) return st;
    // Vertices welded within tol: a hash of cells of size 4 tol; a vertex takes the representative
    // of the first earlier vertex within tol, looked for in its own cell and, along each axis where
    // it lies within tol (a quarter cell, 0.26 for rounding) of a cell boundary, the cell beyond:
    // copies that round to either side of a boundary still meet, and most vertices look in one cell.
    struct CellKey {
        std::int64_t x, y, z;
        bool operator==(const CellKey&) const = default;
    };
    struct CellHash {
        std::size_t operator()(const CellKey& k) const {
            return static_cast<std::size_t>(mix(static_cast<std::uint64_t>(k.x) ^ mix(static_cast<std::uint64_t>(k.y) ^
                                                                                     mix(static_cast<std::uint64_t>(k.z)))));
        }
    };
    const Bounds bb = bounds_of(model);
    const double h = 4 * tol;
    constexpr std::uint32_t kUnset = std::numeric_limits<std::uint32_t>::max();
    std::vector<std::uint32_t> rep(model.positions.size(), kUnset), next(model.positions.size(), kUnset);
    std::unordered_map<CellKey, std::uint32_t, CellHash> head;  // cell → its first vertex; next[] chains the rest
    head.reserve(model.positions.size());
    const auto weld = [&](std::uint32_t v) {
        if (rep[v] != kUnset) return rep[v];
        const Vec3& p = model.positions[v];
        const Vec3 r = (p - bb.lo) / h;
        const CellKey c{static_cast<std::int64_t>(std::floor(r.x)), static_cast<std::int64_t>(std::floor(r.y)),
                        static_cast<std::int64_t>(std::floor(r.z))};
        std::array<std::array<std::int64_t, 2>, 3> off{};  // per axis: 0, and -1 or +1 (or 0 again)
        for (int k = 0; k < 3; ++k) {
            const double f = r[k] - std::floor(r[k]);
            off[k] = {0, f < 0.26 ? -1 : f > 0.74 ? 1 : 0};
        }
        for (int a = 0; a < 2 && rep[v] == kUnset; ++a)
            for (int b2 = 0; b2 < 2 && rep[v] == kUnset; ++b2)
                for (int d = 0; d < 2 && rep[v] == kUnset; ++d) {
                    if ((a && !off[0][1]) || (b2 && !off[1][1]) || (d && !off[2][1])) continue;
                    const auto it = head.find(CellKey{c.x + off[0][a], c.y + off[1][b2], c.z + off[2][d]});
                    if (it == head.end()) continue;
                    for (std::uint32_t u = it->second; u != kUnset; u = next[u])
                        if (glm::length(model.positions[u] - p) <= tol) {
                            rep[v] = rep[u];
                            break;
                        }
                }
        if (rep[v] == kUnset) {
            rep[v] = v;
            const auto [it, inserted] = head.try_emplace(c, v);
            if (!inserted) next[v] = std::exchange(it->second, v);
        }
        return rep[v];
    };
    // A face's key: its welded vertex cycle, consecutive repeats dropped, rotated to start at its
    // least vertex (the reverse cycle, so rotated, is the other side of the same sheet). Keys are
    // kept flat; faces are sorted by the key's hash and compared within equal hashes: O(n log n),
    // no allocation per face, and the same answer on every run.
    std::vector<std::uint32_t> flat;
    std::vector<std::size_t> start(model.faces.size() + 1, 0);
    std::vector<std::pair<std::uint64_t, std::uint32_t>> forward, reverse;  // (hash, face)
    std::vector<std::uint32_t> key;
    const auto canonical = [](std::vector<std::uint32_t>& k) {
        std::rotate(k.begin(), std::min_element(k.begin(), k.end()), k.end());
    };
    const auto hash_of = [](const std::vector<std::uint32_t>& k) {
        std::uint64_t x = k.size();
        for (const std::uint32_t v : k) x = mix(x ^ v);
        return x;
    };
    for (std::size_t fi = 0; fi < model.faces.size(); ++fi) {
        key.clear();
        for (const std::uint32_t v : model.faces[fi].v) {
            const std::uint32_t r = weld(v);
            if (key.empty() || key.back() != r) key.push_back(r);
        }
        while (key.size() > 1 && key.back() == key.front()) key.pop_back();
        if (key.size() >= 3) {  // fewer: degenerate, the mesher drops it
            canonical(key);
            flat.insert(flat.end(), key.begin(), key.end());
            forward.emplace_back(hash_of(key), static_cast<std::uint32_t>(fi));
            std::reverse(key.begin(), key.end());
            canonical(key);
            reverse.emplace_back(hash_of(key), static_cast<std::uint32_t>(fi));
        }
        start[fi + 1] = flat.size();
    }
    const auto same = [&](std::uint32_t f, std::uint32_t g, bool reversed) {
        const std::size_t n = start[f + 1] - start[f];
        if (start[g + 1] - start[g] != n) return false;
        const std::uint32_t* a = flat.data() + start[f];
        const std::uint32_t* b = flat.data() + start[g];
        if (!reversed) return std::equal(a, a + n, b);
        // g's cycle reversed and rotated to its least vertex (b[0], which is also a's least).
        if (a[0] != b[0]) return false;
        for (std::size_t k = 1; k < n; ++k)
            if (a[k] != b[n - k]) return false;
        return true;
    };
    std::sort(forward.begin(), forward.end());
    std::vector<std::uint8_t> drop(model.faces.size(), 0);
    std::vector<std::pair<std::size_t, std::size_t>> examples;  // (duplicate, original), by duplicate
    for (std::size_t lo = 0, hi = 0; lo < forward.size(); lo = hi) {
        for (hi = lo + 1; hi < forward.size() && forward[hi].first == forward[lo].first;) ++hi;
        for (std::size_t x = lo + 1; x < hi; ++x)  // faces in increasing order: the first copy stays
            for (std::size_t y = lo; y < x; ++y)
                if (!drop[forward[y].second] && same(forward[x].second, forward[y].second, false)) {
                    drop[forward[x].second] = 1;
                    examples.emplace_back(forward[x].second, forward[y].second);
                    break;
                }
    }
    std::sort(examples.begin(), examples.end());
    if (examples.size() > kNamed) examples.resize(kNamed);
    // Two-sided sheets: a kept face whose reverse cycle is an earlier kept face's cycle.
    for (const auto& [hash, f] : reverse) {
        if (drop[f]) continue;
        auto it = std::lower_bound(forward.begin(), forward.end(), std::make_pair(hash, std::uint32_t{0}));
        for (; it != forward.end() && it->first == hash && it->second < f; ++it)
            if (!drop[it->second] && same(it->second, f, true)) {
                ++st.two_sided_pairs;
                break;
            }
    }
    for (const std::uint8_t d : drop) st.duplicates_removed += d;
    if (st.duplicates_removed == 0) return st;
    std::string list;
    for (const auto& [dup, orig] : examples)
        list += fmt::format("{}{} repeats {}", list.empty() ? "" : "; ", named(model, dup), named(model, orig));
    st.warnings.push_back(fmt::format(
        "{}: removed {} duplicate face{} (the same vertices, within {:.3g}, in the same order as an earlier face: each copy "
        "would get the whole form factor again){}: {}{}",
        model.source, st.duplicates_removed, st.duplicates_removed == 1 ? "" : "s", tol,
        st.two_sided_pairs ? fmt::format("; {} faces with an earlier face's vertices in reverse order stay (two-sided sheets)",
                                         st.two_sided_pairs)
                           : std::string(),
        list, st.duplicates_removed > examples.size() ? ", ..." : ""));
    std::size_t out = 0;
    for (std::size_t fi = 0; fi < model.faces.size(); ++fi)
        if (!drop[fi]) {
            if (out != fi) model.faces[out] = std::move(model.faces[fi]);  // never a self-move (it would empty v)
            ++out;
        }
    model.faces.resize(out);
    return st;
}

}  // namespace ffcube
