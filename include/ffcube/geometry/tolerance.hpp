// Tolerances for geometric tests that scale with the coordinates (docs/robustness.md).
#pragma once

#include "ffcube/geometry/polygon.hpp"

#include <span>

namespace ffcube {

// Largest |coordinate| of any vertex (max over x, y, z): the magnitude that sets the rounding of
// the vertices themselves. 0 for an empty span.
double max_abs_coordinate(std::span<const Vec3> poly);

// The one rule for "zero up to rounding" in geometric tests (planarity, a point or vertex in a
// plane, coincidence, collinearity as a distance): an absolute tolerance in scene units,
//   max(rel_tol × size,  kCoordinateRoundingUlps × ε × coord_max),   ε = 2^-52,
// where `size` is the feature the test is about (a polygon's longest edge, a pair's size) and
// `coord_max` the largest |coordinate| involved (max_abs_coordinate). Why the second term: a
// planar polygon stored in doubles far from the origin has its vertices rounded by half an ulp
// of their coordinates, up to √3/2 · ε · coord_max off its plane, and computing a centroid and a
// deviation from those adds as much again; a polygon of size 2.8e-4 at 1e5 is 7e-12 "off its
// plane", 2.6e-8 of its size. 16 ulps is 8× that worst case; at the origin the term vanishes and
// the size-relative rule decides alone. Other layers (near-field plane tests, hemicube
// T-junctions) call this so that every layer agrees on what counts as rounding.
inline constexpr double kCoordinateRoundingUlps = 16.0;

// The one rule for "planar": a polygon whose vertices lie within kPlanarityTolerance × (longest
// edge) of its Newell plane. The mesher keeps such a face whole (a quad grid); the analytic
// kernels project it onto its plane (analytic.hpp). Beyond it, the mesher triangulates the face.
inline constexpr double kPlanarityTolerance = 1e-6;
double geometric_tolerance(double rel_tol, double size, double coord_max);

}  // namespace ffcube
