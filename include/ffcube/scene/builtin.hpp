// The built-in default scene: the Cornell box (Cornell's measured geometry, its light, red,
// green and white walls), embedded in the binary.
#pragma once

#include <string_view>

#include "ffcube/scene/scene.hpp"

namespace ffcube {

std::string_view cornell_box_obj();
std::string_view cornell_box_mtl();
ObjModel load_cornell_box();

}  // namespace ffcube
