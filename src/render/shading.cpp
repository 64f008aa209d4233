#include "ffcube/render/shading.hpp"

#include <glm/geometric.hpp>

#include <algorithm>
#include <cmath>

#include "ffcube/core/error.hpp"
#include "ffcube/scene/surface_vertices.hpp"

namespace ffcube {
namespace {

// Normals within about 25° (cos 25° ≈ 0.9) count as one surface: the two triangles of a slightly
// non-planar quad (Cornell's left wall, off by 1 mm in 550) shade as one, a 90° corner does not.
constexpr double kSameSurfaceCos = 0.9;

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

    // Smooth: corners at one point form surface vertices (same object, similar normal); each holds
    // Σ A_i v_i / Σ A_i over its patches.
    SurfaceVertices vertices = surface_vertices(scene, kSameSurfaceCos);
    for (const Patch& p : scene.patches) mesh.face_sizes.push_back(static_cast<std::uint8_t>(p.count));
    mesh.values = vertex_average(scene, vertices, patch_values);
    mesh.positions = std::move(vertices.positions);
    mesh.face_indices = std::move(vertices.corner_vertex);
    return mesh;
}

}  // namespace ffcube
