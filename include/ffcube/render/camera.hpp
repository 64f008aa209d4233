// A pinhole camera for pictures of a scene, and the default view that frames one.
#pragma once

#include <string>

#include "ffcube/scene/scene.hpp"

namespace ffcube {

struct Camera {
    Vec3 eye{0.0};
    Vec3 target{0.0, 0.0, 1.0};
    Vec3 up{0.0, 1.0, 0.0};   // need not be orthogonal to the view direction, only not parallel
    double fov_degrees = 39.3;  // vertical field of view
};

// The view a picture of the scene gets when none is given (docs/solve.md):
//  - the built-in Cornell box: the camera of Cornell's data, eye (278, 273, −800) looking at
//    (278, 273, 0), vertical field of view 39.3°;
//  - otherwise the scene is looked at along a coordinate axis, from its open side: the side of the
//    bounding box (−z first, then +z, −x, +x, −y, +y) with the least patch area lying in that side's
//    plane. An open side (none) puts the eye outside, centred, at the distance where a 39.3° view
//    frames the box with 3% to spare; a closed scene puts the eye just inside that side, looking
//    at the opposite side with a field of view wide enough to show the walls around it.
Camera default_camera(const Scene& scene);

// "ex,ey,ez,tx,ty,tz[,fov]" (fov in degrees, in (0, 180)). InputError naming the option and the
// rule otherwise, also when eye and target coincide.
Camera parse_camera(const std::string& text);

}  // namespace ffcube
