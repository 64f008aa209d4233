// The occlusion (shaft) test of near pairs (see shaft_test.hpp).
#include "accuracy/shaft_test.hpp"

#include <glm/common.hpp>
#include <glm/geometric.hpp>

#include <algorithm>
#include <array>
#include <cmath>
#include <utility>

#include "accuracy/near_values.hpp"
#include "ffcube/geometry/tolerance.hpp"

namespace ffcube::accuracy {

namespace {

// The projection [lo, hi] of the hull points on `axis`.
std::pair<double, double> hull_extent(const Vec3& axis, std::span<const Vec3> hull) {
    double hlo = INFINITY, hhi = -INFINITY;
    for (const Vec3& v : hull) {
        const double d = glm::dot(axis, v);
        hlo = std::min(hlo, d);
        hhi = std::max(hhi, d);
    }
    return {hlo, hhi};
}

// Whether the hull's projection on `axis` (extent) and q's overlap by at most tol.
bool separated(const Vec3& axis, std::pair<double, double> extent, const Poly& q, double tol) {
    double qlo = INFINITY, qhi = -INFINITY;
    for (std::size_t k = 0; k < q.n; ++k) {
        const double d = glm::dot(axis, q.v[k]);
        qlo = std::min(qlo, d);
        qhi = std::max(qhi, d);
    }
    return extent.second <= qlo + tol || qhi <= extent.first + tol;
}

bool separated(const Vec3& axis, std::span<const Vec3> hull, const Poly& q, double tol) {
    return separated(axis, hull_extent(axis, hull), q, tol);
}

// Whether the segment a → b crosses the interior of the convex polygon q (unit normal nq, its
// corners counter-clockwise about it) so deep that no unit axis u separates q from a convex set
// holding a and b, even allowing an overlap of tol (separated() above). Proof: let the segment
// cross q's plane at p = a + t (b − a), at an angle whose sine is δ = |nq · d| (d the unit
// direction), with a disc of radius r about p inside q. On an axis u with in-plane part s, q's
// extent holds u·p ± r s and the set's holds u·a and u·b, so both ends overlap by at least
// max(r s, min(t, 1 − t) L |u·d|), L = |b − a|. Where s ≥ δ/2 that is ≥ r δ/2; else |u·nq| ≥
// √(1 − δ²/4) and |u·d| ≥ 0.866 δ − δ/2 > 0.366 δ. Required: both above 100 tol (the rounding of
// these few operations is some 1e-16 of the coordinates, tol at least 1e-9 of the pair's size).
bool crosses_deep(const Poly& q, const Vec3& nq, const Vec3& a, const Vec3& b, double tol) {
    const Vec3 ab = b - a;
    const double len = glm::length(ab);
    if (!(len > 0)) return false;
    const double ga = glm::dot(nq, a - q.v[0]), gb = glm::dot(nq, b - q.v[0]);
    if (!((ga > 0 && gb < 0) || (ga < 0 && gb > 0))) return false;
    const double t = ga / (ga - gb);
    const Vec3 p = a + t * ab;
    const double delta = std::abs(ga - gb) / len;
    const double m = std::min(t, 1 - t) * len;
    double r = INFINITY;
    for (std::size_t k = 0; k < q.n; ++k) {
        const Vec3 e = q.v[(k + 1) % q.n] - q.v[k];
        const Vec3 in = glm::cross(nq, e);
        const double il = glm::length(in);
        if (!(il > 0)) return false;
        r = std::min(r, glm::dot(in, p - q.v[k]) / il);
    }
    return 0.5 * r * delta > 100 * tol && 0.366 * delta * m > 100 * tol;
}

}  // namespace

// Candidate axes: the normals of q, i and j; the cross products of q's edges with every segment
// between two hull points (the edge–edge axes of the full test); and the normals of every plane
// through three hull points (the hull's face planes are among them).
namespace {

// Visits every candidate q of the pair's shaft with whether an axis separates it from the hull,
// until on_candidate returns false; returns whether it never did.
// first: a patch to test before the grid's (skipped there), or UINT32_MAX.
template <class OnCandidate>
bool visit_shaft(const PatchSet& patches, const SpatialGrid& grid, std::uint32_t i, std::uint32_t j,
                 ShaftScratch& scratch, std::uint32_t first, OnCandidate&& on_candidate) {
    const Scene& scene = patches.scene;
    const Box pair = patches.pair_box(i, j);
    const double scale = glm::length(pair.hi - pair.lo);
    // Relative tolerance of touching: a q that enters the hull by less than 1e-9 of the pair's
    // size blocks at most a sliver of that relative width (documented in docs/accuracy.md); far
    // from the origin, never less than the rounding of the coordinates (geometry/tolerance.hpp),
    // or a neighbour touching the pair would count as entering the shaft by rounding alone.
    const double coord = std::max({std::abs(pair.lo.x), std::abs(pair.lo.y), std::abs(pair.lo.z), std::abs(pair.hi.x),
                                   std::abs(pair.hi.y), std::abs(pair.hi.z)});
    const double tol = geometric_tolerance(1e-9, scale, coord);
    // The shaft is the hull of the parts of i and j in front of each other's plane: only
    // segments between those carry radiation (cos θ ≤ 0 elsewhere), and the near value is the
    // form factor of exactly those parts (exact_ff and separated_ff clip both polygons the same
    // way). A ground triangle reaching under a wall, or a wall reaching below a floor, no
    // longer drags its hidden part (and what stands on it) into the shaft. Each plane is moved
    // back by tol, so the hull also holds what the near value's lift (within tol of the plane)
    // brings in front. A triangle clipped by a plane has at most 4 vertices, a quad 5.
    std::array<Vec3, 10> hull_points{};
    std::size_t m = 0;
    std::size_t split = 0;  // hull_points[0, split): i's part; [split, m): j's
    for (const auto& [a, b] : {std::pair{i, j}, std::pair{j, i}}) {
        if (a == j) split = m;
        const Patch& pb = scene.patches[b];
        const std::size_t from = m;
        clip_front_each(patches.polys[a].span(), pb.centroid - tol * pb.normal, pb.normal,
                        [&](const Vec3& v) { hull_points[m++] = v; });
        // facing() found a vertex tol in front: fewer than 3 would be rounding; keep the whole.
        if (m - from < 3) {
            m = from;
            for (const Vec3& v : patches.polys[a].span()) hull_points[m++] = v;
        }
    }
    const std::span<const Vec3> hull(hull_points.data(), m);
    // Candidates: the patches whose boxes meet the hull's (a q whose box misses it is separated
    // by an axis of the box), which is smaller than the pair's where a part was clipped off.
    Box inflated{hull[0], hull[0]};
    for (const Vec3& v : hull) inflated = Box{glm::min(inflated.lo, v), glm::max(inflated.hi, v)};
    inflated = Box{inflated.lo - Vec3(tol), inflated.hi + Vec3(tol)};
    // The blocker tried first (`first`: shaft_unoccluded's last one), if it crosses the segment
    // between the two parts' vertex means (points of the hull) deep inside: not separated by any
    // axis, so the answer is known before the axes are made.
    const bool tried = first < patches.size() && first != i && first != j && patches.boxes[first].overlaps(inflated);
    Vec3 ci(0.0), cj(0.0);
    for (std::size_t k = 0; k < split; ++k) ci += hull[k];
    for (std::size_t k = split; k < m; ++k) cj += hull[k];
    ci /= static_cast<double>(split);
    cj /= static_cast<double>(m - split);
    if (tried && crosses_deep(patches.polys[first], scene.patches[first].normal, ci, cj, tol) &&
        !on_candidate(first, false)) {
        ++scratch.deep_crossings;
        return false;
    }
    // The axes of the full test, made when a candidate first needs them: the hull-only axes are
    // the same for every q (the normals of i, j and of every plane through three hull points,
    // the hull's face planes among them) and so are their hull extents; the segments between
    // hull points make q's edge–edge axes.
    std::vector<Vec3>& axes = scratch.axes;
    std::vector<std::pair<double, double>>& extent = scratch.axis_extent;
    std::vector<Vec3>& seg = scratch.segments;
    bool made = false;
    const auto make_axes = [&]() {
        made = true;
        axes.clear();
        axes.push_back(scene.patches[i].normal);
        axes.push_back(scene.patches[j].normal);
        for (std::size_t a = 0; a < m; ++a)
            for (std::size_t b = a + 1; b < m; ++b)
                for (std::size_t c = b + 1; c < m; ++c) {
                    const Vec3 nrm = glm::cross(hull[b] - hull[a], hull[c] - hull[a]);
                    if (glm::dot(nrm, nrm) > 1e-24 * scale * scale * scale * scale) axes.push_back(glm::normalize(nrm));
                }
        extent.clear();
        for (const Vec3& axis : axes) extent.push_back(hull_extent(axis, hull));
        seg.clear();
        for (std::size_t a = 0; a < m; ++a)
            for (std::size_t b = a + 1; b < m; ++b) seg.push_back(hull[b] - hull[a]);
    };

    // Every candidate must be separated: the answer does not depend on the order, so the grid's
    // visit stops at the first that is not (refused pairs, most of a city's, stop early). A q
    // that the segment between the parts' centres crosses deep inside is not separated by any
    // axis (crosses_deep): the same answer as the full test, without its axes.
    const auto test = [&](std::uint32_t qi) {
        const Poly& q = patches.polys[qi];
        const Vec3& nq = scene.patches[qi].normal;
        bool sep = separated(nq, hull, q, tol);
        if (!sep && crosses_deep(q, nq, ci, cj, tol)) return on_candidate(qi, false);
        if (!sep && !made) make_axes();
        for (std::size_t a = 0; !sep && a < axes.size(); ++a) sep = separated(axes[a], extent[a], q, tol);
        for (std::size_t e = 0; !sep && e < q.n; ++e) {
            const Vec3 edge = q.v[(e + 1) % q.n] - q.v[e];
            for (std::size_t s = 0; !sep && s < seg.size(); ++s) {
                const Vec3 axis = glm::cross(edge, seg[s]);
                const double len2 = glm::dot(axis, axis);
                if (len2 <= 1e-24 * scale * scale * scale * scale) continue;
                sep = separated(axis / std::sqrt(len2), hull, q, tol);
            }
        }
        return on_candidate(qi, sep);
    };
    if (tried && !test(first)) return false;
    return grid.visit(inflated, [&](std::uint32_t qi) {
        if (qi == i || qi == j || (tried && qi == first)) return true;
        return test(qi);
    });
}

}  // namespace

bool shaft_unoccluded(const PatchSet& patches, const SpatialGrid& grid, std::uint32_t i, std::uint32_t j,
                      ShaftScratch& scratch) {
    return visit_shaft(patches, grid, i, j, scratch, scratch.last_blocker, [&](std::uint32_t q, bool sep) {
        if (!sep) scratch.last_blocker = q;
        return sep;
    });
}

bool shaft_blockers(const PatchSet& patches, const SpatialGrid& grid, std::uint32_t i, std::uint32_t j,
                    ShaftScratch& scratch, std::vector<std::uint32_t>& blockers, std::size_t max) {
    blockers.clear();
    const bool few = visit_shaft(patches, grid, i, j, scratch, UINT32_MAX, [&](std::uint32_t q, bool sep) {
        if (!sep) blockers.push_back(q);
        return blockers.size() <= max;
    });
    std::sort(blockers.begin(), blockers.end());
    return few;
}

}  // namespace ffcube::accuracy
