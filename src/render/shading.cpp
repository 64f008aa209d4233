#include "ffcube/render/shading.hpp"

#include <glm/geometric.hpp>

#include <algorithm>
#include <cmath>
#include <tuple>
#include <unordered_map>

#include "ffcube/core/error.hpp"

namespace ffcube {
namespace {

// Normals within about 25° (cos 25° ≈ 0.9) count as one surface: the two triangles of a slightly
// non-planar quad (Cornell's left wall, off by 1 mm in 550) shade as one, a 90° corner does not.
constexpr double kSameSurfaceCos = 0.9;

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

ShadedMesh shade_patches(const Scene& scene, std::span<const Vec3> patch_values, Shading shading) {
    FFCUBE_CHECK(patch_values.size() == scene.size());
    ShadedMesh mesh;
    mesh.face_sizes.reserve(scene.size());
    mesh.face_indices.reserve(scene.size() * 4);
    if (shading == Shading::Flat) {
        for (std::size_t i = 0; i < scene.size(); ++i) {
            const Patch& p = scene.patches[i];
            mesh.face_sizes.push_back(static_cast<std::uint8_t>(p.count));
            for (std::uint32_t c = 0; c < p.count; ++c) {
                mesh.face_indices.push_back(static_cast<std::uint32_t>(mesh.positions.size()));
                mesh.positions.push_back(scene.positions[p.v[c]]);
                mesh.values.push_back(patch_values[i]);
            }
        }
        return mesh;
    }

    // Smooth: corners at one point form clusters (same object, similar normal); each cluster is
    // one output vertex holding Σ A_i v_i / Σ A_i over its patches.
    const double quantum = std::max(scene.extent(), 1e-300) * 1e-7;
    const auto key_of = [&](const Vec3& p) {
        return Key{std::llround(p.x / quantum), std::llround(p.y / quantum), std::llround(p.z / quantum)};
    };
    struct Cluster {
        std::uint32_t object;
        Vec3 normal;
        Vec3 weighted{0.0};
        double area = 0.0;
        std::uint32_t vertex;  // output index
    };
    std::unordered_map<Key, std::vector<Cluster>, KeyHash> at_point;
    at_point.reserve(scene.positions.size());
    std::vector<std::uint32_t> corner_vertex;  // per patch corner, in face_indices order
    corner_vertex.reserve(scene.size() * 4);
    for (std::size_t i = 0; i < scene.size(); ++i) {
        const Patch& p = scene.patches[i];
        mesh.face_sizes.push_back(static_cast<std::uint8_t>(p.count));
        for (std::uint32_t c = 0; c < p.count; ++c) {
            const Vec3& pos = scene.positions[p.v[c]];
            std::vector<Cluster>& clusters = at_point[key_of(pos)];
            Cluster* found = nullptr;
            for (Cluster& cl : clusters)
                if (cl.object == p.object && glm::dot(cl.normal, p.normal) > kSameSurfaceCos) {
                    found = &cl;
                    break;
                }
            if (!found) {
                clusters.push_back(Cluster{p.object, p.normal, Vec3(0.0), 0.0,
                                           static_cast<std::uint32_t>(mesh.positions.size())});
                mesh.positions.push_back(pos);
                found = &clusters.back();
            }
            found->weighted += p.area * patch_values[i];
            found->area += p.area;
            corner_vertex.push_back(found->vertex);
        }
    }
    mesh.values.assign(mesh.positions.size(), Vec3(0.0));
    for (const auto& [key, clusters] : at_point)
        for (const Cluster& cl : clusters) mesh.values[cl.vertex] = cl.weighted / cl.area;
    mesh.face_indices = std::move(corner_vertex);
    return mesh;
}

}  // namespace ffcube
