// NIST View3D input (.vs3, geometry format F 3): T, C, F, V, S and End lines. Each S surface is
// an object named by its name field; surfaces combined with `cmb` are one object named by the
// base surface; the emissivity becomes the material (Kd = 1 − ε, an opaque grey surface). O, M
// and N surfaces and subsurfaces (base ≠ 0) are refused (not supported yet); control keys that
// ffcube does not honour are listed in the warnings. Every refusal names the file and the line.
#pragma once

#include <filesystem>
#include <string>
#include <string_view>

#include "ffcube/scene/scene.hpp"

namespace ffcube {

ObjModel parse_vs3(std::string_view text, const std::string& source);

ObjModel load_vs3(const std::filesystem::path& path);

}  // namespace ffcube
