// The hemicube's local frame on a patch, and the per-patch rotation about the normal that keeps
// the pixel grid's aliasing from lining up with the scene (one seeded angle per patch, so runs
// stay deterministic).
#pragma once

#include "ffcube/geometry/polygon.hpp"

#include <cstdint>

namespace ffcube {

// Orthonormal, right-handed: tangent × bitangent = normal. Local coordinates (x, y, z) are
// along (tangent, bitangent, normal), the frame of layout.hpp's faces.
struct HemicubeFrame {
    Vec3 tangent, bitangent, normal;

    Vec3 to_world(const Vec3& local) const {
        return local.x * tangent + local.y * bitangent + local.z * normal;
    }
    Vec3 to_local(const Vec3& world) const;
};

// Frame around `normal` (any non-zero finite vector; it is normalised), with the tangent
// rotated by `angle` radians about the normal (counter-clockwise seen from the normal's tip)
// from a reference tangent that depends only on the normal. The reference basis is Duff et
// al., "Building an Orthonormal Basis, Revisited" (JCGT 6(1), 2017): branch-free on the sign
// of n.z and accurate for every unit normal, including n = (0,0,-1) where Frisvad's 2012
// version fails. A zero or non-finite normal is a bug upstream (degenerate patches are
// dropped by the mesher): FFCUBE_CHECK.
HemicubeFrame make_frame(const Vec3& normal, double angle);

// splitmix64 finaliser (Steele, Lea, Flood 2014): a bijective 64-bit mix.
std::uint64_t splitmix64(std::uint64_t x);

// Deterministic pseudo-random rotation of patch `patch`'s hemicube for run seed `seed`, in
// [0, 2π), never within 5° of a multiple of 90° (where the pixel grid lines up with axis-aligned
// edges). Same (seed, patch) → same angle on every machine and thread count.
double hemicube_angle(std::uint64_t seed, std::uint32_t patch);

}  // namespace ffcube
