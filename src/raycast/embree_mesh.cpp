#include "raycast/embree_mesh.hpp"

#include <fmt/format.h>

#include "ffcube/core/error.hpp"

namespace ffcube {

void build_embree_mesh(const Scene& scene, EmbreeMesh& out, const char* who, const char* config) {
    // Centre and scale the scene to unit size before converting to float: a scene offset by
    // 1e5 or scaled by 1e-4 then keeps float's full relative precision.
    out.center = 0.5 * (scene.bbox_min + scene.bbox_max);
    const double ext = scene.extent();
    out.scale = ext > 0 ? 1.0 / ext : 1.0;
    EmbreeHandles& embree = out.embree;
    embree.device = rtcNewDevice(config);
    if (!embree.device)
        throw InternalError(fmt::format("{}: Embree device could not be created (error {})", who,
                                        static_cast<int>(rtcGetDeviceError(nullptr))));
    embree.scene = rtcNewScene(embree.device);
    rtcSetSceneFlags(embree.scene, RTC_SCENE_FLAG_ROBUST);
    rtcSetSceneBuildQuality(embree.scene, RTC_BUILD_QUALITY_HIGH);
    RTCGeometry geom = rtcNewGeometry(embree.device, RTC_GEOMETRY_TYPE_TRIANGLE);
    auto* vb = static_cast<float*>(rtcSetNewGeometryBuffer(geom, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3,
                                                           3 * sizeof(float), scene.positions.size()));
    for (std::size_t k = 0; k < scene.positions.size(); ++k) {
        const Vec3 p = (scene.positions[k] - out.center) * out.scale;
        vb[3 * k + 0] = static_cast<float>(p.x);
        vb[3 * k + 1] = static_cast<float>(p.y);
        vb[3 * k + 2] = static_cast<float>(p.z);
    }
    std::size_t ntri = 0;
    for (const Patch& p : scene.patches) ntri += p.count == 4 ? 2 : 1;
    auto* ib = static_cast<unsigned*>(
        rtcSetNewGeometryBuffer(geom, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3, 3 * sizeof(unsigned), ntri));
    out.tri_patch.clear();
    out.tri_patch.reserve(ntri);
    std::size_t t = 0;
    for (std::uint32_t i = 0; i < scene.size(); ++i) {
        const Patch& p = scene.patches[i];
        ib[3 * t + 0] = p.v[0], ib[3 * t + 1] = p.v[1], ib[3 * t + 2] = p.v[2], ++t;
        out.tri_patch.push_back(i);
        if (p.count == 4) {
            ib[3 * t + 0] = p.v[0], ib[3 * t + 1] = p.v[2], ib[3 * t + 2] = p.v[3], ++t;
            out.tri_patch.push_back(i);
        }
    }
    rtcCommitGeometry(geom);
    rtcAttachGeometry(embree.scene, geom);
    rtcReleaseGeometry(geom);
    rtcCommitScene(embree.scene);
    const RTCError err = rtcGetDeviceError(embree.device);
    if (err != RTC_ERROR_NONE)
        throw InternalError(fmt::format("{}: Embree scene build failed (error {})", who, static_cast<int>(err)));
}

}  // namespace ffcube
