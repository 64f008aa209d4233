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

Box PatchSet::pair_box(std::uint32_t i, std::uint32_t j) const {
    return Box{glm::min(boxes[i].lo, boxes[j].lo), glm::max(boxes[i].hi, boxes[j].hi)};
}

}  // namespace ffcube::accuracy
