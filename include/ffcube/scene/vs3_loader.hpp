// NIST View3D input (.vs3, geometry format F 3): T, C, F, V, S and End lines. Each S surface is
// an object named by its name field; surfaces combined with `cmb` are one object named by the
// base surface; the emissivity becomes the material (Kd = 1 − ε, an opaque grey surface). O
// surfaces are obstruction-only objects (ObjModel::obstruction_objects). A subsurface (base ≠ 0)
// or a null surface (N) lies on its base, inside it: the base keeps what they leave of it, as
// convex pieces (faces of the base's object); an N surface is also an obstruction-only object.
// Masking surfaces (M) are refused (not supported yet); control keys that ffcube does not honour
// are listed in the warnings. Every refusal names the file and the line.
#pragma once

#include <filesystem>
#include <string>
#include <string_view>

#include "ffcube/scene/scene.hpp"

namespace ffcube {

ObjModel parse_vs3(std::string_view text, const std::string& source);

ObjModel load_vs3(const std::filesystem::path& path);

}  // namespace ffcube
