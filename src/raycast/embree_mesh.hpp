// Internal to the raycast layer. One job: the scene's patches as one Embree triangle mesh (quads
// as two triangles), centred and scaled to unit size, shared by the row provider and RayScene.
#pragma once

#include <embree3/rtcore.h>

#include <cmath>
#include <cstdint>
#include <limits>
#include <vector>

#include "ffcube/scene/scene.hpp"

namespace ffcube {

// The Embree device and scene, released together.
struct EmbreeHandles {
    RTCDevice device = nullptr;
    RTCScene scene = nullptr;
    EmbreeHandles() = default;
    EmbreeHandles(const EmbreeHandles&) = delete;
    EmbreeHandles& operator=(const EmbreeHandles&) = delete;
    ~EmbreeHandles() {
        if (scene) rtcReleaseScene(scene);
        if (device) rtcReleaseDevice(device);
    }
};

// The mesh in Embree coordinates, (p − center) · scale, and the patch of each Embree primitive.
struct EmbreeMesh {
    EmbreeHandles embree;
    std::vector<std::uint32_t> tri_patch;  // Embree primID → patch index
    Vec3 center{0.0};
    double scale = 1.0;
};

// Builds and commits the mesh of a non-empty scene. Throws InternalError when Embree cannot
// start or build; `who` names the caller in the message.
// `config`: Embree's device configuration (rtcNewDevice), e.g. "threads=1"; nullptr: its defaults.
void build_embree_mesh(const Scene& scene, EmbreeMesh& out, const char* who, const char* config = nullptr);

inline constexpr std::uint32_t kNoPatch = std::numeric_limits<std::uint32_t>::max();

// How many times a ray is traced at most, past hits on its own patch (float rounding).
inline constexpr int kRetraces = 4;

// The first patch j that the ray o + t·d (Embree coordinates, t ≥ tnear) meets with pass(j)
// false. A hit with pass(j) true (the ray's own patch: float rounding) is traced on past,
// `attempts` traces in all; then, or when the ray leaves the scene, kNoPatch. traced counts the
// rtcIntersect1 calls.
template <class Pass>
std::uint32_t first_patch(const EmbreeMesh& m, RTCIntersectContext& ctx, const Vec3& o, const Vec3& d, Pass&& pass,
                          std::uint64_t& traced, float tnear = 0.0f, int attempts = 4) {
    RTCRayHit rh;
    rh.ray.org_x = static_cast<float>(o.x);
    rh.ray.org_y = static_cast<float>(o.y);
    rh.ray.org_z = static_cast<float>(o.z);
    rh.ray.dir_x = static_cast<float>(d.x);
    rh.ray.dir_y = static_cast<float>(d.y);
    rh.ray.dir_z = static_cast<float>(d.z);
    rh.ray.tnear = tnear;
    rh.ray.time = 0.0f;
    rh.ray.mask = 0xFFFFFFFFu;
    rh.ray.id = 0;
    rh.ray.flags = 0;
    for (int attempt = 0; attempt < attempts; ++attempt) {
        rh.ray.tfar = std::numeric_limits<float>::infinity();
        rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
        rh.hit.primID = RTC_INVALID_GEOMETRY_ID;
        rtcIntersect1(m.embree.scene, &ctx, &rh);
        ++traced;
        if (rh.hit.geomID == RTC_INVALID_GEOMETRY_ID) return kNoPatch;  // left the scene
        const std::uint32_t j = m.tri_patch[rh.hit.primID];
        if (!pass(j)) return j;
        rh.ray.tnear = std::nextafter(rh.ray.tfar, std::numeric_limits<float>::infinity());
    }
    return kNoPatch;
}

}  // namespace ffcube
