// A-priori discontinuity meshing at contact lines (Heckbert; Lischinski, Tampieri and Greenberg:
// D0 discontinuities), a preprocessing step on the model before meshing (docs/adaptive.md,
// "Contact cuts").
//
// Where another object stands on a receiver face (a block on the floor), the radiosity of the
// receiver jumps along the contact polygon: inside it the floor sees only the block's back faces
// and is seen by nothing. A patch that straddles the contact line is counted lit or dark whole,
// which is a first-order error in the patch size. cut_contacts() cuts each receiver face along the
// contact polygon, so that no patch straddles it: the face is replaced by convex faces inside
// the polygon (the covered part, kept as faces of the receiver's object, so that object means are
// over the same area) and outside it.
//
// A contact polygon of object B on a planar convex face R of another object is
//   * a face of B coplanar with R and facing the other way (a block's bottom face), or
//   * a closed loop of edges of B's faces that lie in R's plane, those faces standing on R's front
//     side (a block without a bottom face: its side faces' bottom edges),
// clipped to R. "In the plane" is geometry/tolerance.hpp's rule with kPlanarityTolerance × R's
// size. Loops that are not convex are left alone and counted (skipped).
#pragma once

#include <cstddef>
#include <string>
#include <vector>

#include "ffcube/scene/scene.hpp"

namespace ffcube {

struct ContactCutStats {
    std::size_t contacts = 0;   // contact polygons cut into receiver faces
    std::size_t receivers = 0;  // receiver faces that were cut
    std::size_t faces = 0;      // convex faces those receivers became
    double covered_area = 0.0;  // area of those faces inside contact polygons, scene units²
    std::size_t skipped = 0;    // closed contact loops left alone (not convex)
    std::vector<std::string> notes;  // one line per skipped loop (file:line of the receiver), the first 10
};

// Cuts the receivers of `model` in place (faces replaced in their place in face order, new
// vertices appended to positions). Deterministic: depends on the model only.
ContactCutStats cut_contacts(ObjModel& model);

}  // namespace ffcube
