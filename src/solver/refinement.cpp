// The refinement indicator and marking of adaptive meshing (solver/refinement.hpp).
#include "ffcube/solver/refinement.hpp"

#include <glm/geometric.hpp>

#include <algorithm>
#include <cmath>
#include <numeric>
#include <unordered_map>

#include "ffcube/core/error.hpp"
#include "ffcube/solver/solver.hpp"

namespace ffcube {
namespace {

// cos 25°: the smooth-shading rule of render/solved_scene (same surface).
constexpr double kSameSurfaceCos = 0.9063077870366499;

// Centroids hashed into cubes of side `cell` (the largest patch size × 1.5, so that every
// neighbour within 0.75 (size_i + size_j) is in the 27 cubes around a patch).
struct CentroidHash {
    double cell = 1.0;
    std::unordered_map<std::uint64_t, std::vector<std::uint32_t>> cubes;

    static std::uint64_t key(std::int64_t x, std::int64_t y, std::int64_t z) {
        const auto u = [](std::int64_t v) { return static_cast<std::uint64_t>(v + (1 << 20)) & 0x1fffff; };
        return u(x) | (u(y) << 21) | (u(z) << 42);
    }
    std::array<std::int64_t, 3> at(const Vec3& p) const {
        return {static_cast<std::int64_t>(std::floor(p.x / cell)), static_cast<std::int64_t>(std::floor(p.y / cell)),
                static_cast<std::int64_t>(std::floor(p.z / cell))};
    }
};

}  // namespace

double radiosity_luminance(const Vec3& b) { return 0.2126 * b.r + 0.7152 * b.g + 0.0722 * b.b; }

std::vector<double> radiosity_variation(const Scene& scene, std::span<const Vec3> radiosity) {
    FFCUBE_CHECK_MSG(radiosity.size() == scene.size(), "one radiosity per patch");
    const std::size_t n = scene.size();
    std::vector<double> out(n, 0.0);
    if (n == 0) return out;
    double largest = 0.0;
    for (const Patch& p : scene.patches) largest = std::max(largest, p.size);
    CentroidHash hash;
    // Cubes of at least 2^-20 of the scene's extent keep the 21-bit keys within range.
    hash.cell = std::max(1.5 * largest, scene.extent() * std::ldexp(1.0, -19));
    for (std::uint32_t i = 0; i < n; ++i) {
        const auto c = hash.at(scene.patches[i].centroid);
        hash.cubes[CentroidHash::key(c[0], c[1], c[2])].push_back(i);
    }
    for (std::uint32_t i = 0; i < n; ++i) {
        const Patch& p = scene.patches[i];
        const double yi = radiosity_luminance(radiosity[i]);
        const auto c = hash.at(p.centroid);
        double jump = 0.0;
        for (std::int64_t dz = -1; dz <= 1; ++dz)
            for (std::int64_t dy = -1; dy <= 1; ++dy)
                for (std::int64_t dx = -1; dx <= 1; ++dx) {
                    const auto it = hash.cubes.find(CentroidHash::key(c[0] + dx, c[1] + dy, c[2] + dz));
                    if (it == hash.cubes.end()) continue;
                    for (const std::uint32_t j : it->second) {
                        const Patch& q = scene.patches[j];
                        if (j == i || q.object != p.object || glm::dot(p.normal, q.normal) < kSameSurfaceCos) continue;
                        if (glm::length(p.centroid - q.centroid) > 0.75 * (p.size + q.size)) continue;
                        jump = std::max(jump, std::abs(yi - radiosity_luminance(radiosity[j])));
                    }
                }
        out[i] = 0.5 * jump;
    }
    return out;
}

RefinementChoice choose_refinement(const Scene& scene, std::span<const Vec3> radiosity, double target,
                                   std::size_t max_elements, std::uint32_t factor, double fraction) {
    FFCUBE_CHECK_MSG(fraction > 0.0 && fraction <= 1.0, "the marked fraction is in (0, 1]");
    FFCUBE_CHECK_MSG(factor >= 2, "a split factor is at least 2");
    FFCUBE_CHECK_MSG(target >= 0.0, "the target error is not negative");
    const std::size_t n = scene.size();
    const std::vector<double> variation = radiosity_variation(scene, radiosity);
    const std::vector<ObjectRadiosity> objects = object_radiosity(scene, radiosity);
    RefinementChoice choice;
    choice.split.assign(n, 1);
    choice.elements_after = n;
    std::vector<std::uint32_t> candidates;
    for (std::uint32_t i = 0; i < n; ++i) {
        const double mean = radiosity_luminance(objects[scene.patches[i].object].radiosity);
        if (variation[i] > target * mean && variation[i] > 0.0) candidates.push_back(i);
    }
    choice.candidates = candidates.size();
    std::stable_sort(candidates.begin(), candidates.end(), [&](std::uint32_t a, std::uint32_t b) {
        return variation[a] * scene.patches[a].area > variation[b] * scene.patches[b].area;
    });
    const std::size_t extra = static_cast<std::size_t>(factor) * factor - 1;
    double total = 0.0, marked = 0.0;
    for (const std::uint32_t i : candidates) total += variation[i] * scene.patches[i].area;
    for (const std::uint32_t i : candidates) {
        if (marked >= fraction * total) break;
        if (choice.elements_after + extra > max_elements) {
            choice.budget_limited = true;
            break;
        }
        choice.split[i] = factor;
        marked += variation[i] * scene.patches[i].area;
        choice.elements_after += extra;
        ++choice.marked;
    }
    return choice;
}

}  // namespace ffcube
