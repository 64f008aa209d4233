// Scenes made in code: named polygons turned into an ObjModel, as if read from an OBJ file (one
// face per polygon, objects in order of first use, the default material). Used by the bench's
// analytic cases and by tests.
#pragma once

#include <string>
#include <vector>

#include "ffcube/scene/scene.hpp"

namespace ffcube {

struct NamedPolygon {
    std::string object;          // object name
    std::vector<Vec3> vertices;  // counter-clockwise seen from the front
};

// 'source' names the model in messages (e.g. "<bench case parallel_d1>").
ObjModel model_from_polygons(const std::vector<NamedPolygon>& polygons, const std::string& source);

}  // namespace ffcube
