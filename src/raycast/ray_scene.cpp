#include "ffcube/raycast/ray_scene.hpp"

#include <glm/geometric.hpp>

#include "raycast/embree_mesh.hpp"

namespace ffcube {

struct RayScene::Impl {
    const Scene& scene;
    EmbreeMesh mesh;
    explicit Impl(const Scene& s) : scene(s) {
        // One thread: the scene is built where the hemicube's workers may still have to be
        // forked (the plan's exposed points, in the main process), and Embree's own threads
        // outlive its device: with them this process could no longer fork workers.
        if (scene.size() != 0) build_embree_mesh(scene, mesh, "ray scene", "threads=1");
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
    std::uint64_t traced = 0;
    const std::uint32_t j = first_patch(m, ctx, o, dir, [&](std::uint32_t q) { return q == skip; }, traced);
    if (j == kNoPatch) return {};
    return {j, glm::dot(dir, impl_->scene.patches[j].normal) > 0.0};
}

}  // namespace ffcube
