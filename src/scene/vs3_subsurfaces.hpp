// View3D subsurfaces, masks and null surfaces (../shared/formats/view3d.md; View3D's manual,
// "Surface Types"): a surface lying on its base surface, wholly inside it. The base keeps only
// what the subsurfaces leave of it: its polygon minus theirs, cut into convex pieces (triangles
// and convex quads, so that every piece is a patch as given under --no-subdivide). Pure geometry,
// no file format: vs3_loader.cpp applies it and names the line in its errors.
#pragma once

#include <span>
#include <string>
#include <vector>

#include "ffcube/geometry/polygon.hpp"

namespace ffcube::detail {

// Why `sub` cannot lie on `base` as View3D requires, or "" when it can: every vertex of sub within
// 1e-6 of the base's size (kPlanarityTolerance) of the base's plane and inside the base (convex,
// counter-clockwise from its front), and sub facing the same way as the base (`same_facing`, a
// subsurface) or the opposite way (a mask or null surface): normals within 0.999 (View3D's test).
std::string subsurface_problem(std::span<const Vec3> base, std::span<const Vec3> sub, bool same_facing);

// Area of the intersection of two convex polygons in one plane (either orientation): subsurfaces
// of one base must not overlap (View3D would subtract the overlap twice).
double convex_overlap_area(std::span<const Vec3> a, std::span<const Vec3> b);

// `base` (a convex polygon, counter-clockwise from its front) minus the convex `holes` (each
// inside it, in its plane, in either orientation; they may touch the base's edges or each other
// but not overlap), as convex polygons of 3 or 4 vertices that tile the rest, counter-clockwise
// like the base. Pieces thinner than 1e-9 of the base's size are left out. Without holes: the base.
std::vector<std::vector<Vec3>> cut_holes(std::span<const Vec3> base, const std::vector<std::vector<Vec3>>& holes);

}  // namespace ffcube::detail
