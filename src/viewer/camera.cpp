#include "ffcube/viewer/camera.hpp"

#include <glm/gtc/matrix_transform.hpp>

#include <algorithm>
#include <cmath>
#include <numbers>

namespace ffcube {
namespace {

glm::vec3 direction(float yaw, float pitch) {
    return {std::sin(yaw) * std::cos(pitch), std::sin(pitch), -std::cos(yaw) * std::cos(pitch)};
}

}  // namespace

OrbitCamera OrbitCamera::frame(const Scene& scene) {
    OrbitCamera c;
    const Vec3 centre = 0.5 * (scene.bbox_min + scene.bbox_max);
    c.target_ = glm::vec3(centre);
    c.radius_ = std::max(static_cast<float>(0.5 * scene.extent()), 1e-6f);
    // A sphere of radius r fills the vertical field of view from r / sin(fov/2); 5% margin.
    c.distance_ = 1.05f * c.radius_ / std::sin(0.5f * kFovY);

    const float pi = std::numbers::pi_v<float>;
    const float yaws[4] = {0.0f, pi, 0.5f * pi, -0.5f * pi};
    double best = INFINITY;
    for (float yaw : yaws) {
        const Vec3 d(direction(yaw, 0.0f));
        double blocking = 0.0;  // area facing away from an eye on side d, between it and the centre
        for (const Patch& p : scene.patches)
            if (glm::dot(p.normal, d) < -0.5 && glm::dot(p.centroid - centre, d) > 0.0) blocking += p.area;
        if (blocking < best) best = blocking, c.yaw_ = yaw;
    }
    c.pitch_ = 0.0f;
    return c;
}

void OrbitCamera::orbit(float dx, float dy) {
    const float limit = 89.0f * std::numbers::pi_v<float> / 180.0f;
    yaw_ += 0.01f * dx;
    pitch_ = std::clamp(pitch_ + 0.01f * dy, -limit, limit);
}

void OrbitCamera::pan(float dx, float dy, int height_px) {
    // At the target's depth the viewport spans 2·d·tan(fov/2) scene units vertically.
    const float units_per_px = 2.0f * distance_ * std::tan(0.5f * kFovY) / static_cast<float>(std::max(height_px, 1));
    const glm::mat4 v = view();
    const glm::vec3 right(v[0][0], v[1][0], v[2][0]), up(v[0][1], v[1][1], v[2][1]);
    // The scene moves with the mouse, so the target moves the other way; screen y grows downwards.
    target_ += units_per_px * (-dx * right + dy * up);
}

void OrbitCamera::zoom(float steps) {
    distance_ = std::clamp(distance_ * std::pow(0.9f, steps), 0.01f * radius_, 100.0f * radius_);
}

glm::vec3 OrbitCamera::eye() const { return target_ + distance_ * direction(yaw_, pitch_); }

glm::mat4 OrbitCamera::view() const { return glm::lookAt(eye(), target_, glm::vec3(0.0f, 1.0f, 0.0f)); }

glm::mat4 OrbitCamera::projection(float aspect) const {
    // Clip planes follow the scene's size and the eye's distance, never absolute units.
    const float near_plane = std::max(distance_ - 2.0f * radius_, 1e-3f * radius_);
    const float far_plane = distance_ + 2.0f * radius_;
    return glm::perspective(kFovY, aspect, near_plane, far_plane);
}

}  // namespace ffcube
