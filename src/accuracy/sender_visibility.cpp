// Whether an occluder stands close to a sender (see sender_visibility.hpp).
#include "accuracy/sender_visibility.hpp"

#include <glm/geometric.hpp>

#include <algorithm>
#include <array>
#include <cmath>

#include "ffcube/geometry/polygon.hpp"

namespace ffcube::accuracy {

SenderVisibility::SenderVisibility(const PatchSet& patches, const SpatialGrid& grid, double k)
    : patches_(patches), grid_(grid), k_(k) {
    if (patches.size() == 0) return;
    scene_box_ = patches.boxes[0];
    for (const Box& b : patches.boxes) {
        scene_box_.lo = glm::min(scene_box_.lo, b.lo);
        scene_box_.hi = glm::max(scene_box_.hi, b.hi);
    }
}

namespace {

// Distance from p to box b (0 inside).
double box_distance(const Box& b, const Vec3& p) {
    const Vec3 d = glm::max(glm::max(b.lo - p, p - b.hi), Vec3(0.0));
    return glm::length(d);
}

}  // namespace

// Declared in sender_visibility.hpp.
bool segment_inside(const std::vector<std::array<double, 2>>& poly, const std::array<double, 2>& a,
                    const std::array<double, 2>& b, double margin) {
    double t0 = 0, t1 = 1;
    for (std::size_t k = 0; k < poly.size(); ++k) {
        const auto& e0 = poly[k];
        const auto& e1 = poly[(k + 1) % poly.size()];
        const double mx = -(e1[1] - e0[1]), my = e1[0] - e0[0];  // inward (counter-clockwise)
        const double len = std::hypot(mx, my);
        const double f0 = (mx * (a[0] - e0[0]) + my * (a[1] - e0[1])) / len - margin;
        const double f1 = (mx * (b[0] - e0[0]) + my * (b[1] - e0[1])) / len - margin;
        if (f0 < 0 && f1 < 0) return false;
        if (f0 < 0) t0 = std::max(t0, f0 / (f0 - f1));
        if (f1 < 0) t1 = std::min(t1, f0 / (f0 - f1));
    }
    return (t1 - t0) * std::hypot(b[0] - a[0], b[1] - a[1]) > margin;
}

bool covers_part(const PatchSet& patches, std::uint32_t i, std::uint32_t q) {
    const Patch& pi = patches.scene.patches[i];
    const Patch& pq = patches.scene.patches[q];
    const double tol = 2 * plane_tolerance(pi, pq);
    const Poly& poly = patches.polys[q];
    double lo = INFINITY, hi = -INFINITY;
    for (std::size_t v = 0; v < poly.n; ++v) {
        const double d = glm::dot(pi.normal, poly.v[v] - pi.centroid);
        lo = std::min(lo, d);
        hi = std::max(hi, d);
    }
    if (!(lo >= -tol && hi > tol && hi <= kCoverGap * pi.size)) return false;
    if (!(glm::dot(pq.normal, pi.centroid - pq.centroid) < -tol)) return false;  // i sees q's back
    // In i's plane, lengths in units of i's size: i's outline (counter-clockwise about its
    // normal) and q's edges projected; margin 1e-6 (far above rounding, far below a patch).
    Vec3 t, b;
    orthonormal_basis(pi.normal, t, b);
    const auto local = [&](const Vec3& x) {
        return std::array<double, 2>{glm::dot(x - pi.centroid, t) / pi.size, glm::dot(x - pi.centroid, b) / pi.size};
    };
    std::vector<std::array<double, 2>> outline;
    for (const Vec3& v : patches.polys[i].span()) outline.push_back(local(v));
    for (std::size_t v = 0; v < poly.n; ++v)
        if (segment_inside(outline, local(poly.v[v]), local(poly.v[(v + 1) % poly.n]), 1e-6)) return true;
    return false;
}


int SenderVisibility::occluder_level(std::uint32_t i, std::vector<std::uint32_t>& near) const {
    const Scene& scene = patches_.scene;
    const Patch& pi = scene.patches[i];
    const double reach = k_ * std::max(pi.size, patches_.max_size);
    grid_.query(Box{pi.centroid - Vec3(reach), pi.centroid + Vec3(reach)}, near);
    return occluder_level_of_candidates(i, near);
}

int SenderVisibility::occluder_level_of_candidates(std::uint32_t i, const std::vector<std::uint32_t>& near) const {
    const Scene& scene = patches_.scene;
    const Patch& pi = scene.patches[i];
    int level = 0;
    for (const std::uint32_t q : near) {
        if (q == i) continue;
        const Patch& pq = scene.patches[q];
        if (glm::length(pq.centroid - pi.centroid) >= k_ * std::max(pi.size, pq.size)) continue;
        const double tol = 2 * plane_tolerance(pi, pq);
        // q rises in front of i's plane (a coplanar neighbour, or anything behind it, cannot
        // hide part of i's hemisphere).
        const Poly& poly = patches_.polys[q];
        double rise = -INFINITY;
        for (std::size_t v = 0; v < poly.n; ++v) rise = std::max(rise, glm::dot(pi.normal, poly.v[v] - pi.centroid));
        if (!(rise > tol)) continue;
        // Something may lie beyond q's plane, seen from i: a corner of the scene's box strictly on
        // the other side of it from i's centroid (either side when the centroid is in the plane).
        const double side = glm::dot(pq.normal, pi.centroid - pq.centroid);
        // Seen from behind (i's centre inside a block standing on it): q shows its back, the
        // centre sees nothing past it, and neither do points under the block; but a cover
        // (covers_part: a plate just in front of i over part of it) leaves the rest of i open.
        if (side < -tol) {
            if (covers_part(patches_, i, q)) return 2;
            continue;
        }
        bool behind = false;
        for (int c = 0; c < 8 && !behind; ++c) {
            const Vec3 corner(c & 1 ? scene_box_.hi.x : scene_box_.lo.x, c & 2 ? scene_box_.hi.y : scene_box_.lo.y,
                              c & 4 ? scene_box_.hi.z : scene_box_.lo.z);
            const double s = glm::dot(pq.normal, corner - pq.centroid);
            behind = (side > tol && s < -tol) || (side < -tol && s > tol) || (std::abs(side) <= tol && std::abs(s) > tol);
        }
        if (!behind) continue;
        if (box_distance(patches_.boxes[q], pi.centroid) < pi.size) return 2;
        level = 1;
    }
    return level;
}

}  // namespace ffcube::accuracy
