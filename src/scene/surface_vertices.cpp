// Patch corners grouped into surface vertices (scene/surface_vertices.hpp).
#include "ffcube/scene/surface_vertices.hpp"

#include <glm/geometric.hpp>

#include <algorithm>
#include <cmath>
#include <unordered_map>

#include "ffcube/core/error.hpp"

namespace ffcube {
namespace {

struct Key {
    long long x, y, z;
    bool operator==(const Key&) const = default;
};
struct KeyHash {
    std::size_t operator()(const Key& k) const {
        std::size_t h = static_cast<std::size_t>(k.x) * 0x9E3779B97F4A7C15ull;
        h ^= static_cast<std::size_t>(k.y) + 0x9E3779B97F4A7C15ull + (h << 6) + (h >> 2);
        h ^= static_cast<std::size_t>(k.z) + 0x9E3779B97F4A7C15ull + (h << 6) + (h >> 2);
        return h;
    }
};

}  // namespace

SurfaceVertices surface_vertices(const Scene& scene, double same_surface_cos) {
    SurfaceVertices out;
    const double quantum = std::max(scene.extent(), 1e-300) * 1e-7;
    const auto key_of = [&](const Vec3& p) {
        return Key{std::llround(p.x / quantum), std::llround(p.y / quantum), std::llround(p.z / quantum)};
    };
    struct Cluster {
        std::uint32_t object;
        Vec3 normal;
        std::uint32_t vertex;
    };
    std::unordered_map<Key, std::vector<Cluster>, KeyHash> at_point;
    at_point.reserve(scene.positions.size());
    out.corner_vertex.reserve(scene.size() * 4);
    out.first_corner.reserve(scene.size());
    for (std::size_t i = 0; i < scene.size(); ++i) {
        const Patch& p = scene.patches[i];
        out.first_corner.push_back(static_cast<std::uint32_t>(out.corner_vertex.size()));
        for (std::uint32_t c = 0; c < p.count; ++c) {
            const Vec3& pos = scene.positions[p.v[c]];
            std::vector<Cluster>& clusters = at_point[key_of(pos)];
            const auto found = std::find_if(clusters.begin(), clusters.end(), [&](const Cluster& cl) {
                return cl.object == p.object && glm::dot(cl.normal, p.normal) > same_surface_cos;
            });
            if (found != clusters.end()) {
                out.corner_vertex.push_back(found->vertex);
                continue;
            }
            const auto v = static_cast<std::uint32_t>(out.positions.size());
            clusters.push_back(Cluster{p.object, p.normal, v});
            out.positions.push_back(pos);
            out.corner_vertex.push_back(v);
        }
    }
    return out;
}

std::vector<Vec3> vertex_average(const Scene& scene, const SurfaceVertices& vertices, std::span<const Vec3> patch_values) {
    FFCUBE_CHECK(patch_values.size() == scene.size() && vertices.first_corner.size() == scene.size());
    std::vector<Vec3> sum(vertices.positions.size(), Vec3(0.0));
    std::vector<double> area(vertices.positions.size(), 0.0);
    for (std::size_t i = 0; i < scene.size(); ++i) {
        const Patch& p = scene.patches[i];
        for (std::uint32_t c = 0; c < p.count; ++c) {
            const std::uint32_t v = vertices.corner_vertex[vertices.first_corner[i] + c];
            sum[v] += p.area * patch_values[i];
            area[v] += p.area;
        }
    }
    for (std::size_t v = 0; v < sum.size(); ++v)
        if (area[v] > 0.0) sum[v] /= area[v];
    return sum;
}

}  // namespace ffcube
