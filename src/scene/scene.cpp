#include "ffcube/scene/scene.hpp"
#include "ffcube/scene/patch_areas.hpp"

#include <glm/geometric.hpp>

#include <cmath>

namespace ffcube {

double Scene::extent() const { return glm::length(bbox_max - bbox_min); }

std::array<Vec3, 4> Scene::patch_vertices(std::size_t i) const {
    const Patch& p = patches[i];
    return {positions[p.v[0]], positions[p.v[1]], positions[p.v[2]], positions[p.v[p.count == 4 ? 3 : 2]]};
}

std::vector<double> patch_areas(const Scene& scene) {
    std::vector<double> areas;
    areas.reserve(scene.size());
    for (const Patch& p : scene.patches) areas.push_back(p.area);
    return areas;
}

double Scene::total_area() const {
    // Neumaier-compensated: millions of small areas summed naively lose ~n·eps relative.
    double sum = 0.0, compensation = 0.0;
    for (const Patch& p : patches) {
        const double t = sum + p.area;
        compensation += std::abs(sum) >= p.area ? (sum - t) + p.area : (p.area - t) + sum;
        sum = t;
    }
    return sum + compensation;
}

}  // namespace ffcube
