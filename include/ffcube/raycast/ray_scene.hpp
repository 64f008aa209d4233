// One ray at a time through the scene's patches (Embree 3, the ray caster's mesh): which patch a
// ray meets first, and on which side. For geometric questions that are not form factors (which
// parts of a sender lie inside a building: gl/exposed_points.hpp).
#pragma once

#include <cstdint>
#include <limits>
#include <memory>

#include "ffcube/scene/scene.hpp"

namespace ffcube {

class RayScene {
public:
    // Builds the mesh (RaycastRowProvider's). Throws InternalError when Embree cannot start.
    // The scene must outlive this. Const queries are thread-safe.
    explicit RayScene(const Scene& scene);
    ~RayScene();

    static constexpr std::uint32_t kNone = std::numeric_limits<std::uint32_t>::max();
    struct Hit {
        std::uint32_t patch = kNone;  // kNone: the ray left the scene
        bool back = false;            // it met the patch's back (dot(dir, normal) > 0)
    };
    // The first patch met by origin + t·dir, t > 0, other than `skip` (a ray's own patch, which
    // float rounding may report): traced on past it a few times at most. dir need not be unit.
    Hit first_hit(const Vec3& origin, const Vec3& dir, std::uint32_t skip = kNone) const;

private:
    struct Impl;
    std::unique_ptr<Impl> impl_;
};

}  // namespace ffcube
