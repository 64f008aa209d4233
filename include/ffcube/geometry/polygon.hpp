// Planar polygons in double precision. Vertices are counter-clockwise seen from the front,
// so the normal (Newell) points to the front side.
#pragma once

#include <glm/vec3.hpp>

#include <span>

namespace ffcube {

using Vec3 = glm::dvec3;

// Newell's vector: twice the vector area. Its length is 2 × area; its direction, the normal.
Vec3 newell_vector(std::span<const Vec3> poly);
// Area in scene units² (0 for fewer than 3 vertices).
double polygon_area(std::span<const Vec3> poly);
// Unit front normal; (0,0,0) for a degenerate polygon.
Vec3 polygon_normal(std::span<const Vec3> poly);
// Area centroid of a planar polygon (falls back to the vertex mean when degenerate).
Vec3 polygon_centroid(std::span<const Vec3> poly);
// Largest distance of a vertex from the polygon's best-fit plane (through the centroid, along
// the Newell normal), in scene units. 0 for triangles.
double polygon_planarity_deviation(std::span<const Vec3> poly);
// Longest edge length in scene units.
double polygon_max_edge(std::span<const Vec3> poly);

// Orthonormal tangents t, b of a unit normal n, with t × b = n (Duff et al. 2017, "Building an
// Orthonormal Basis, Revisited", listing 3: branchless, accurate for every n). The one copy: the
// hemicube frame, the ray caster's directions and the analytic kernels all use it.
void orthonormal_basis(const Vec3& n, Vec3& t, Vec3& b);

}  // namespace ffcube
