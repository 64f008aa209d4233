// The per-patch geometry shared by the accuracy layer's pieces (see patch_set.hpp).
#include "accuracy/patch_set.hpp"

#include <glm/geometric.hpp>

#include <algorithm>
#include <cmath>
#include <limits>

#include "ffcube/geometry/tolerance.hpp"

namespace ffcube::accuracy {

double plane_tolerance(const Patch& a, const Patch& b) {
    const double coord = std::max({std::abs(a.centroid.x), std::abs(a.centroid.y), std::abs(a.centroid.z),
                                   std::abs(b.centroid.x), std::abs(b.centroid.y), std::abs(b.centroid.z)});
    return geometric_tolerance(1e-9, std::max(a.size, b.size), coord);
}

PatchSet::PatchSet(const Scene& s) : scene(s) {
    const std::size_t n = s.size();
    polys.resize(n);
    boxes.resize(n);
    radius.resize(n);
    sizes.resize(n);
    for (std::size_t i = 0; i < n; ++i) {
        const Patch& p = s.patches[i];
        polys[i].n = p.count;
        for (std::size_t k = 0; k < p.count; ++k) polys[i].v[k] = s.positions[p.v[k]];
        Box b{polys[i].v[0], polys[i].v[0]};
        for (std::size_t k = 1; k < p.count; ++k) {
            b.lo = glm::min(b.lo, polys[i].v[k]);
            b.hi = glm::max(b.hi, polys[i].v[k]);
        }
        boxes[i] = b;
        for (std::size_t k = 0; k < p.count; ++k) radius[i] = std::max(radius[i], glm::length(polys[i].v[k] - p.centroid));
        sizes[i] = p.size;
        max_size = std::max(max_size, p.size);
    }
}

bool PatchSet::facing(std::uint32_t i, std::uint32_t j) const {
    const Patch& pi = scene.patches[i];
    const Patch& pj = scene.patches[j];
    const double tol = 2 * plane_tolerance(pi, pj);
    const Poly& qi = polys[i];
    const Poly& qj = polys[j];
    double front_j = -INFINITY, front_i = -INFINITY;
    for (std::size_t v = 0; v < qj.n; ++v) front_j = std::max(front_j, glm::dot(pi.normal, qj.v[v] - pi.centroid));
    for (std::size_t v = 0; v < qi.n; ++v) front_i = std::max(front_i, glm::dot(pj.normal, qi.v[v] - pj.centroid));
    return front_j > tol && front_i > tol;
}

bool PatchSet::straddles(std::uint32_t i, std::uint32_t j) const {
    const Patch& pj = scene.patches[j];
    const double tol = plane_tolerance(scene.patches[i], pj);
    bool front = false, back = false;
    for (std::size_t v = 0; v < polys[i].n; ++v) {
        const double h = glm::dot(pj.normal, polys[i].v[v] - pj.centroid);
        front = front || h > tol;
        back = back || h < -tol;
    }
    return front && back;
}

double PatchSet::distance(const Vec3& p, std::uint32_t j) const {
    const Poly& q = polys[j];
    const Vec3& n = scene.patches[j].normal;
    bool inside = true;
    double nearest = INFINITY;
    for (std::size_t a = 0; a < q.n; ++a) {
        const Vec3& u = q.v[a];
        const Vec3 e = q.v[(a + 1) % q.n] - u;
        // Outside this edge (the outline runs counter-clockwise about the normal).
        if (glm::dot(glm::cross(e, p - u), n) < 0) inside = false;
        const double t = std::clamp(glm::dot(p - u, e) / std::max(glm::dot(e, e), 1e-300), 0.0, 1.0);
        nearest = std::min(nearest, glm::length(u + t * e - p));
    }
    return inside ? std::min(nearest, std::abs(glm::dot(p - scene.patches[j].centroid, n))) : nearest;
}

Box PatchSet::pair_box(std::uint32_t i, std::uint32_t j) const {
    return Box{glm::min(boxes[i].lo, boxes[j].lo), glm::max(boxes[i].hi, boxes[j].hi)};
}

}  // namespace ffcube::accuracy
