#include "ffcube/render/solved_scene.hpp"

#include <numbers>

#include "ffcube/core/error.hpp"
#include "ffcube/render/image.hpp"

namespace ffcube {

std::vector<Vec3> patch_radiance(std::span<const Vec3> radiosity) {
    std::vector<Vec3> radiance(radiosity.size());
    for (std::size_t i = 0; i < radiosity.size(); ++i) radiance[i] = radiosity[i] / std::numbers::pi;
    return radiance;
}

double scene_exposure(const Scene& scene, std::span<const Vec3> radiance, std::optional<double> given) {
    if (given) return *given;
    FFCUBE_CHECK(radiance.size() == scene.size());
    std::vector<double> lum(scene.size()), area(scene.size());
    for (std::size_t i = 0; i < scene.size(); ++i) {
        lum[i] = luminance(radiance[i]);
        area[i] = scene.patches[i].area;
    }
    return auto_exposure(lum, area);
}

PlyMesh solved_ply_mesh(const Scene& scene, std::span<const Vec3> radiosity, Shading shading, double exposure) {
    const ShadedMesh shaded = shade_patches(scene, radiosity, shading);
    PlyMesh ply;
    ply.positions = shaded.positions;
    for (Vec3& x : ply.positions) x += scene.origin;  // the user's coordinates (Scene::origin)
    ply.values = shaded.values;
    ply.colors.reserve(shaded.values.size());
    for (const Vec3& b : shaded.values) {
        const Vec3 l = b / std::numbers::pi;
        ply.colors.push_back({encode_srgb8(l.r, exposure), encode_srgb8(l.g, exposure), encode_srgb8(l.b, exposure)});
    }
    ply.face_sizes = shaded.face_sizes;
    ply.face_indices = shaded.face_indices;
    return ply;
}

}  // namespace ffcube
