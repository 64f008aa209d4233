// Internal to the scene layer: the mesher's triangulation of a polygon that is not a convex
// planar quad, shared with the defect checks (defects.cpp), which must look at the triangles
// the mesher will make.
#pragma once

#include <array>
#include <span>
#include <vector>

#include "ffcube/geometry/polygon.hpp"

namespace ffcube::detail {

// Ear clipping in the plane of unit_normal. Ears are convex corners with no other vertex inside;
// when rounding leaves none (a self-touching or non-simple polygon), the most convex corner is
// cut so that the loop always ends. Triangles keep the polygon's orientation.
void ear_clip(std::span<const Vec3> poly, const Vec3& unit_normal, std::vector<std::array<Vec3, 3>>& out);

}  // namespace ffcube::detail
