#include "ffcube/raycast/ray_scene.hpp"

#include <glm/geometric.hpp>

#include <cmath>
#include <limits>

#include "raycast/embree_mesh.hpp"

namespace ffcube {

struct RayScene::Impl {
    const Scene& scene;
    EmbreeMesh mesh;
    explicit Impl(const Scene& s) : scene(s) {
        if (scene.size() != 0) build_embree_mesh(scene, mesh, "ray scene");
    }
};

RayScene::RayScene(const Scene& scene) : impl_(std::make_unique<Impl>(scene)) {}
RayScene::~RayScene() = default;

RayScene::Hit RayScene::first_hit(const Vec3& origin, const Vec3& dir, std::uint32_t skip) const {
    const EmbreeMesh& m = impl_->mesh;
    if (!m.embree.scene) return {};
    const Vec3 o = (origin - m.center) * m.scale;
    RTCIntersectContext ctx;
    rtcInitIntersectContext(&ctx);
    RTCRayHit rh;
    rh.ray.org_x = static_cast<float>(o.x);
    rh.ray.org_y = static_cast<float>(o.y);
    rh.ray.org_z = static_cast<float>(o.z);
    rh.ray.dir_x = static_cast<float>(dir.x);
    rh.ray.dir_y = static_cast<float>(dir.y);
    rh.ray.dir_z = static_cast<float>(dir.z);
    rh.ray.tnear = 0.0f;
    rh.ray.time = 0.0f;
    rh.ray.mask = 0xFFFFFFFFu;
    rh.ray.id = 0;
    rh.ray.flags = 0;
    for (int attempt = 0; attempt < 4; ++attempt) {
        rh.ray.tfar = std::numeric_limits<float>::infinity();
        rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
        rh.hit.primID = RTC_INVALID_GEOMETRY_ID;
        rtcIntersect1(m.embree.scene, &ctx, &rh);
        if (rh.hit.geomID == RTC_INVALID_GEOMETRY_ID) return {};
        const std::uint32_t j = m.tri_patch[rh.hit.primID];
        if (j != skip) return {j, glm::dot(dir, impl_->scene.patches[j].normal) > 0.0};
        rh.ray.tnear = std::nextafter(rh.ray.tfar, std::numeric_limits<float>::infinity());
    }
    return {};
}

}  // namespace ffcube
