// --materials FILE: Kd and Ke per object for formats that have no materials (STL, View3D, PLY, ...).
// A CSV file, one object per line:
//   object,kd_r,kd_g,kd_b,ke_r,ke_g,ke_b
// A first line starting with "object," is a header; lines starting with '#' and blank lines are
// skipped. Kd within [0,1], Ke finite and ≥ 0, as in MTL. Every object the model has that the
// file names gets a material of its own (named after the object); objects the file does not name
// keep theirs; a name the model does not have is a warning. A triple left empty (",,,": all three
// fields) keeps what the scene file gave: e.g. "box,,,,1,1,1" lights a PLY's object while each of
// its faces keeps its own Kd (then one material per material the object's faces had).
#pragma once

#include <filesystem>
#include <string>
#include <string_view>

#include "ffcube/scene/scene.hpp"

namespace ffcube {

void apply_material_map(ObjModel& model, std::string_view csv, const std::string& source);

void apply_material_map_file(ObjModel& model, const std::filesystem::path& path);

}  // namespace ffcube
