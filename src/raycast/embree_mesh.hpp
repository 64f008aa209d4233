// Internal to the raycast layer. One job: the scene's patches as one Embree triangle mesh (quads
// as two triangles), centred and scaled to unit size, shared by the row provider and RayScene.
#pragma once

#include <embree3/rtcore.h>

#include <cstdint>
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
void build_embree_mesh(const Scene& scene, EmbreeMesh& out, const char* who);

}  // namespace ffcube
