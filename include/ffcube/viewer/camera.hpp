// The viewer's orbit camera: pure math, no GL. It circles a target point at a distance, Y up (the
// OBJ convention), and maps mouse motion in pixels to orbit, pan and zoom.
#pragma once

#include <glm/glm.hpp>

#include "ffcube/scene/scene.hpp"

namespace ffcube {

class OrbitCamera {
public:
    // Frames the scene's bounding box: target at its centre, the whole box inside the view. The
    // side to look from is the one of ±x, ±z with the least back-facing area between the eye and
    // the centre (a Cornell box is seen through its open side).
    static OrbitCamera frame(const Scene& scene);

    // Vertical field of view, radians.
    static constexpr float kFovY = 0.7853982f;  // 45°

    // Drag by (dx, dy) pixels: 0.01 rad per pixel; pitch stays within ±89° so "up" never flips.
    void orbit(float dx, float dy);
    // Moves the target so that the point under the cursor at the target's depth follows the mouse:
    // dx pixels right moves that point exactly dx pixels right on a viewport height_px tall.
    void pan(float dx, float dy, int height_px);
    // One wheel notch brings the eye 10% closer (negative steps move away), within
    // [radius / 100, radius × 100] of the target.
    void zoom(float steps);

    glm::mat4 view() const;
    glm::mat4 projection(float aspect) const;
    glm::mat4 view_projection(float aspect) const { return projection(aspect) * view(); }
    glm::vec3 eye() const;
    glm::vec3 target() const { return target_; }
    float distance() const { return distance_; }

private:
    glm::vec3 target_{0.0f};
    float yaw_ = 0.0f, pitch_ = 0.0f;  // radians; yaw 0 puts the eye on -z of the target
    float distance_ = 1.0f;
    float radius_ = 1.0f;  // half the scene's bounding-box diagonal: scales clip planes and zoom limits
};

}  // namespace ffcube
