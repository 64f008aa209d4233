#include "ffcube/render/camera.hpp"

#include <fmt/format.h>
#include <glm/geometric.hpp>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <sstream>
#include <vector>

#include "ffcube/core/error.hpp"

namespace ffcube {

Camera default_camera(const Scene& scene) {
    Camera cam;
    if (scene.source == "<built-in cornell box>") {
        cam.eye = Vec3(278, 273, -800);
        cam.target = Vec3(278, 273, 0);
        return cam;
    }
    const Vec3 lo = scene.bbox_min, hi = scene.bbox_max, size = hi - lo, centre = 0.5 * (lo + hi);
    const double tol = 1e-3 * std::max(scene.extent(), 1e-300);
    // Candidate sides in order of preference: (axis, the eye on the low side?).
    struct Side {
        int axis;
        bool low;
    };
    const Side sides[6] = {{2, true}, {2, false}, {0, true}, {0, false}, {1, true}, {1, false}};
    double best_lid = INFINITY;
    Side best = sides[0];
    for (const Side& s : sides) {
        const double plane = s.low ? lo[s.axis] : hi[s.axis];
        double lid = 0.0;
        for (const Patch& p : scene.patches)
            if (std::abs(p.centroid[s.axis] - plane) <= tol) lid += p.area;
        if (lid < best_lid) {
            best_lid = lid;
            best = s;
        }
    }
    const int a = best.axis, u = (a + 1) % 3, v = (a + 2) % 3;
    Vec3 dir(0.0);
    dir[a] = best.low ? 1.0 : -1.0;  // looking into the box
    cam.up = a == 1 ? Vec3(0, 0, 1) : Vec3(0, 1, 0);
    const double cross = std::max(size[u], size[v]), depth = size[a];
    const double plane = best.low ? lo[a] : hi[a];
    Vec3 face_centre = centre;
    face_centre[a] = plane;
    if (best_lid == 0.0) {
        // Outside: the 39.3° view frames the near side's cross-section with 3% to spare.
        const double tan_half = std::tan(cam.fov_degrees * std::numbers::pi / 360.0);
        const double distance = 1.03 * 0.5 * cross / tan_half;
        cam.eye = face_centre - distance * dir;
        cam.target = face_centre;
    } else {
        // Inside a closed scene: just within the side, wide enough to show the surrounding walls.
        cam.eye = face_centre + 0.02 * depth * dir;
        cam.target = centre + 0.5 * depth * dir;
        const double fov = 2.0 * std::atan(cross / std::max(depth, 1e-300)) * 180.0 / std::numbers::pi;
        cam.fov_degrees = std::clamp(fov, 30.0, 100.0);
    }
    return cam;
}

Camera parse_camera(const std::string& text) {
    std::vector<double> v;
    std::stringstream ss(text);
    std::string item;
    while (std::getline(ss, item, ',')) {
        std::size_t used = 0;
        double x = 0.0;
        try {
            x = std::stod(item, &used);
        } catch (const std::exception&) {
            used = 0;
        }
        if (used == 0 || item.find_first_not_of(" \t", used) != std::string::npos || !std::isfinite(x))
            throw InputError(fmt::format("--camera {}: '{}' is not a finite number (expected ex,ey,ez,tx,ty,tz[,fov])", text, item));
        v.push_back(x);
    }
    if (v.size() != 6 && v.size() != 7)
        throw InputError(fmt::format("--camera {}: expected 6 or 7 comma-separated numbers ex,ey,ez,tx,ty,tz[,fov], got {}",
                                     text, v.size()));
    Camera cam;
    cam.eye = Vec3(v[0], v[1], v[2]);
    cam.target = Vec3(v[3], v[4], v[5]);
    if (v.size() == 7) cam.fov_degrees = v[6];
    if (!(cam.fov_degrees > 0.0 && cam.fov_degrees < 180.0))
        throw InputError(fmt::format("--camera {}: the field of view must lie in (0, 180) degrees", text));
    if (cam.eye == cam.target) throw InputError(fmt::format("--camera {}: eye and target coincide", text));
    // Looking straight up or down: +y cannot be the up direction.
    const Vec3 d = glm::normalize(cam.target - cam.eye);
    if (std::abs(d.y) > 0.999) cam.up = Vec3(0, 0, 1);
    return cam;
}

}  // namespace ffcube
