// The orbit camera's promises, checked by projecting points with its own matrices.
#include <gtest/gtest.h>

#include <cmath>

#include "ffcube/scene/builtin.hpp"
#include "ffcube/scene/mesher.hpp"
#include "ffcube/viewer/camera.hpp"

namespace ffcube {
namespace {

Scene cornell() {
    MeshOptions o;
    o.target_patches = 100;
    return build_scene(load_cornell_box(), o);
}

glm::vec3 ndc(const glm::mat4& vp, glm::vec3 p) {
    const glm::vec4 c = vp * glm::vec4(p, 1.0f);
    EXPECT_GT(c.w, 0.0f) << "point behind the eye";
    return glm::vec3(c) / c.w;
}

// float matrices: projected coordinates in [-1, 1] carry a few ulps of the scene's 560 units, far
// below 1e-4 (a hundredth of a pixel on a 1000-pixel window).
constexpr float kTol = 1e-4f;

TEST(OrbitCamera, FramesTheWholeSceneFromItsOpenSide) {
    const Scene s = cornell();
    const OrbitCamera c = OrbitCamera::frame(s);
    // The built-in box is open at z = 0 and closed elsewhere: only that side shows the inside.
    EXPECT_LT(c.eye().z, s.bbox_min.z);
    const glm::mat4 vp = c.view_projection(1.0f);
    for (int k = 0; k < 8; ++k) {
        const glm::vec3 corner(k & 1 ? s.bbox_max.x : s.bbox_min.x, k & 2 ? s.bbox_max.y : s.bbox_min.y,
                               k & 4 ? s.bbox_max.z : s.bbox_min.z);
        const glm::vec3 p = ndc(vp, corner);
        EXPECT_LE(std::abs(p.x), 1.0f);
        EXPECT_LE(std::abs(p.y), 1.0f);
        EXPECT_GT(p.z, -1.0f);  // inside the clip planes
        EXPECT_LT(p.z, 1.0f);
    }
}

TEST(OrbitCamera, OrbitKeepsTheTargetCentredAtTheSameDistance) {
    OrbitCamera c = OrbitCamera::frame(cornell());
    const float d = c.distance();
    c.orbit(123.0f, -45.0f);
    EXPECT_NEAR(glm::length(c.eye() - c.target()), d, d * kTol);
    const glm::vec3 p = ndc(c.view_projection(1.5f), c.target());
    EXPECT_NEAR(p.x, 0.0f, kTol);
    EXPECT_NEAR(p.y, 0.0f, kTol);
    // Pitch stops short of the pole: dragging far up leaves "up" defined (the eye is not above).
    c.orbit(0.0f, 1e6f);
    const glm::vec3 dir = glm::normalize(c.eye() - c.target());
    EXPECT_NEAR(dir.y, std::sin(89.0f * 3.14159265f / 180.0f), 1e-5f);
}

TEST(OrbitCamera, PanMovesThePointAtTheTargetWithTheMouse) {
    OrbitCamera c = OrbitCamera::frame(cornell());
    c.orbit(40.0f, 20.0f);
    const int width = 800, height = 600;
    const float aspect = static_cast<float>(width) / height;
    const glm::vec3 old_target = c.target();
    c.pan(30.0f, -50.0f, height);  // 30 px right, 50 px up
    const glm::vec3 p = ndc(c.view_projection(aspect), old_target);
    // NDC spans 2 over the viewport: dx pixels are 2·dx/width, and screen y points down.
    EXPECT_NEAR(p.x, 2.0f * 30.0f / width, kTol);
    EXPECT_NEAR(p.y, 2.0f * 50.0f / height, kTol);
}

TEST(OrbitCamera, ZoomScalesTheDistanceWithinLimits) {
    const Scene s = cornell();
    OrbitCamera c = OrbitCamera::frame(s);
    const float d = c.distance();
    c.zoom(2.0f);
    EXPECT_NEAR(c.distance(), d * 0.81f, d * kTol);
    c.zoom(-1000.0f);
    EXPECT_NEAR(c.distance(), 100.0f * 0.5f * static_cast<float>(s.extent()), d * kTol);
}

}  // namespace
}  // namespace ffcube
