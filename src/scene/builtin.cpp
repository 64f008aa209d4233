// The built-in Cornell box. The text is byte-for-byte examples/cornell_box.obj and .mtl (a test
// compares them), so the built-in scene and the example file can never drift apart.
#include "ffcube/scene/builtin.hpp"

#include "ffcube/scene/obj_loader.hpp"

namespace ffcube {
namespace {

constexpr std::string_view kObj = R"cornell(# The Cornell box: the original measured geometry of the Cornell Program of Computer Graphics
# (https://www.graphics.cornell.edu/online/box/data.html), in millimetres. The camera of the
# original data looks along +z from (278, 273, -800); the box is open towards it.
# Faces are wound counter-clockwise seen from their front: walls, floor and ceiling face into the
# box, the blocks face outward, the light faces down. The light hangs 0.1 mm below the ceiling
# (y = 548.7), as renderers of this scene usually place it. The left wall of the measured data
# is not quite planar (its corners lie about 1 mm off a common plane): ffcube triangulates it
# and says so.
# Reflectances and the light's exitance are in cornell_box.mtl.
mtllib cornell_box.mtl

o floor
usemtl white
v 552.8 0.0 0.0
v 0.0 0.0 0.0
v 0.0 0.0 559.2
v 549.6 0.0 559.2
f 1 2 3 4

o ceiling
usemtl white
v 556.0 548.8 0.0
v 556.0 548.8 559.2
v 0.0 548.8 559.2
v 0.0 548.8 0.0
f 5 6 7 8

o back_wall
usemtl white
v 549.6 0.0 559.2
v 0.0 0.0 559.2
v 0.0 548.8 559.2
v 556.0 548.8 559.2
f 9 10 11 12

o right_wall
usemtl green
v 0.0 0.0 559.2
v 0.0 0.0 0.0
v 0.0 548.8 0.0
v 0.0 548.8 559.2
f 13 14 15 16

o left_wall
usemtl red
v 552.8 0.0 0.0
v 549.6 0.0 559.2
v 556.0 548.8 559.2
v 556.0 548.8 0.0
f 17 18 19 20

o light
usemtl light
v 343.0 548.7 227.0
v 343.0 548.7 332.0
v 213.0 548.7 332.0
v 213.0 548.7 227.0
f 21 22 23 24

o short_block
usemtl white
v 130.0 165.0 65.0
v 82.0 165.0 225.0
v 240.0 165.0 272.0
v 290.0 165.0 114.0
v 290.0 0.0 114.0
v 290.0 165.0 114.0
v 240.0 165.0 272.0
v 240.0 0.0 272.0
v 130.0 0.0 65.0
v 130.0 165.0 65.0
v 290.0 165.0 114.0
v 290.0 0.0 114.0
v 82.0 0.0 225.0
v 82.0 165.0 225.0
v 130.0 165.0 65.0
v 130.0 0.0 65.0
v 240.0 0.0 272.0
v 240.0 165.0 272.0
v 82.0 165.0 225.0
v 82.0 0.0 225.0
f 25 26 27 28
f 29 30 31 32
f 33 34 35 36
f 37 38 39 40
f 41 42 43 44

o tall_block
usemtl white
v 423.0 330.0 247.0
v 265.0 330.0 296.0
v 314.0 330.0 456.0
v 472.0 330.0 406.0
v 423.0 0.0 247.0
v 423.0 330.0 247.0
v 472.0 330.0 406.0
v 472.0 0.0 406.0
v 472.0 0.0 406.0
v 472.0 330.0 406.0
v 314.0 330.0 456.0
v 314.0 0.0 456.0
v 314.0 0.0 456.0
v 314.0 330.0 456.0
v 265.0 330.0 296.0
v 265.0 0.0 296.0
v 265.0 0.0 296.0
v 265.0 330.0 296.0
v 423.0 330.0 247.0
v 423.0 0.0 247.0
f 45 46 47 48
f 49 50 51 52
f 53 54 55 56
f 57 58 59 60
f 61 62 63 64
)cornell";

constexpr std::string_view kMtl = R"cornell(# Materials of the Cornell box (cornell_box.obj). Kd: diffuse reflectance per RGB channel, the
# values commonly used for this scene (pbrt, Mitsuba). Ke: emitted radiosity (exitance) per RGB
# channel, pi x (17, 12, 4): a Lambertian emitter of radiance (17, 12, 4), the light of those
# renderers, so that pictures of radiance B/pi compare with theirs.

newmtl white
Kd 0.73 0.73 0.73

newmtl red
Kd 0.63 0.065 0.05

newmtl green
Kd 0.14 0.45 0.091

newmtl light
Kd 0.78 0.78 0.78
Ke 53.407 37.699 12.566
)cornell";

}  // namespace

std::string_view cornell_box_obj() { return kObj; }
std::string_view cornell_box_mtl() { return kMtl; }

ObjModel load_cornell_box() {
    const MtlResolver resolver = [](const std::string& name) -> std::optional<std::string> {
        if (name == "cornell_box.mtl") return std::string(kMtl);
        return std::nullopt;
    };
    return parse_obj(kObj, "<built-in cornell box>", resolver);
}

}  // namespace ffcube
