// Small scenes built in code for tests: polygons with object names, meshed by the real mesher.
#pragma once

#include <string>
#include <vector>

#include "ffcube/scene/mesher.hpp"
#include "ffcube/scene/polygons.hpp"
#include "ffcube/scene/scene.hpp"

namespace ffcube::test {

using ffcube::NamedPolygon;

inline Scene make_scene(const std::vector<NamedPolygon>& polys, double max_patch_edge) {
    MeshOptions o;
    o.max_patch_edge = max_patch_edge;
    return build_scene(model_from_polygons(polys, "<test scene>"), o);
}

// Unit square [0,1]² at height z, facing down (-z) or up (+z).
inline NamedPolygon square_z(const std::string& name, double z, bool facing_up, double size = 1.0, Vec3 offset = Vec3(0.0)) {
    NamedPolygon p{name, {}};
    const Vec3 a = offset + Vec3(0, 0, z), b = offset + Vec3(size, 0, z), c = offset + Vec3(size, size, z),
               d = offset + Vec3(0, size, z);
    p.vertices = facing_up ? std::vector<Vec3>{a, b, c, d} : std::vector<Vec3>{a, d, c, b};
    return p;
}

// Two unit squares at 90° sharing an edge (floor, normal +z; wall in y = 0, normal +y) and a
// two-sided fin standing on the floor near that edge: the plane x = 0.45 from y = 0.05 to 0.4,
// up to z = 0.3 (objects floor, wall, fin_a, fin_b). The floor patches the fin stands on have an
// occluder touching them; pairs across the fin may be occluded.
inline std::vector<NamedPolygon> floor_wall_fin() {
    return {
        {"floor", {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}}},
        {"wall", {{0, 0, 0}, {0, 0, 1}, {1, 0, 1}, {1, 0, 0}}},
        {"fin_a", {{0.45, 0.05, 0}, {0.45, 0.4, 0}, {0.45, 0.4, 0.3}, {0.45, 0.05, 0.3}}},
        {"fin_b", {{0.45, 0.05, 0}, {0.45, 0.05, 0.3}, {0.45, 0.4, 0.3}, {0.45, 0.4, 0}}},
    };
}

// The six inward-facing walls of the axis-aligned box [0,sx]×[0,sy]×[0,sz], objects named
// x0, x1, y0, y1, z0, z1 (the wall at x = 0 is "x0").
inline std::vector<NamedPolygon> inward_box(double sx, double sy, double sz) {
    const Vec3 p000(0, 0, 0), p100(sx, 0, 0), p010(0, sy, 0), p110(sx, sy, 0), p001(0, 0, sz), p101(sx, 0, sz),
        p011(0, sy, sz), p111(sx, sy, sz);
    return {
        {"z0", {p000, p100, p110, p010}},  // floor, normal +z
        {"z1", {p001, p011, p111, p101}},  // ceiling, normal -z
        {"x0", {p000, p010, p011, p001}},  // normal +x
        {"x1", {p100, p101, p111, p110}},  // normal -x
        {"y0", {p000, p001, p101, p100}},  // normal +y
        {"y1", {p010, p110, p111, p011}},  // normal -y
    };
}

// The unit box [0,1]³ (roof and four walls, one-sided, facing out; no floor) on the ground
// [−5,5]² at z = 0 (facing up); one object per face, one patch per face: the scene of the shadow
// closed form in support/box_shadow.hpp.
inline Scene box_on_plane() {
    const std::vector<NamedPolygon> polys{
        {"ground", {{-5, -5, 0}, {5, -5, 0}, {5, 5, 0}, {-5, 5, 0}}},
        {"roof", {{0, 0, 1}, {1, 0, 1}, {1, 1, 1}, {0, 1, 1}}},
        {"south", {{0, 0, 0}, {1, 0, 0}, {1, 0, 1}, {0, 0, 1}}},
        {"east", {{1, 0, 0}, {1, 1, 0}, {1, 1, 1}, {1, 0, 1}}},
        {"north", {{1, 1, 0}, {0, 1, 0}, {0, 1, 1}, {1, 1, 1}}},
        {"west", {{0, 1, 0}, {0, 0, 0}, {0, 0, 1}, {0, 1, 1}}},
    };
    return make_scene(polys, 100.0);
}

}  // namespace ffcube::test
