// Defects that real exports contain, found after loading and before meshing
// (docs/robustness.md, "Defective geometry"): faces written more than once, faces that pass
// through each other, self-intersecting (bow-tie) polygons. Each would otherwise become rows
// that are silently wrong (a duplicated box's rows sum to 2).
#pragma once

#include <cstddef>
#include <string>
#include <vector>

#include "ffcube/scene/scene.hpp"

namespace ffcube {

struct DefectStats {
    std::size_t duplicates_removed = 0;  // faces removed: the same vertices, in the same order, as an earlier face
    std::size_t two_sided_pairs = 0;     // faces with an earlier face's vertices in reverse order: kept (a two-sided sheet)
    std::size_t crossing_pairs = 0;      // pairs of faces that pass through each other (found before the refusal)
    double tolerance = 0;                // the distance within which two vertices count as one (scene units)
    std::vector<std::string> warnings;   // for the caller to print (log_warning) and count
};

// Where a face was written, for messages: "FILE:LINE" or, for a binary STL, "FILE: facet N".
std::string face_place(const ObjModel& model, std::size_t face);

// The distance within which the defect checks take two vertices to be one:
// geometric_tolerance(1e-9, bounding-box diagonal, largest |coordinate|) (geometry/tolerance.hpp).
double coincidence_tolerance(const ObjModel& model);

// Refuses (InputError, naming the file line and object) a polygon whose edges cross each other
// (a bow-tie): its two lobes face opposite ways, so no reading of it is the one the user meant.
void refuse_self_intersecting_faces(const ObjModel& model);

// Removes faces that repeat an earlier face's vertices in the same cyclic order (vertices
// within coincidence_tolerance count as one), keeping the first; faces with the reverse order
// (a two-sided sheet) stay. Objects left without faces keep their names (and no patches).
DefectStats remove_duplicate_faces(ObjModel& model);

// Refuses (InputError) a model in which two faces pass through each other: each has vertices
// strictly on both sides of the other's plane, and their cuts by the other's plane overlap along
// a segment. Touching (a shared edge or vertex, an edge lying on a face, coplanar faces) is not
// crossing. The message names the first pairs by file line and object. Uses a uniform grid over
// the faces' triangles, about linear in the number of faces for ordinary scenes.
// Returns the number of crossing pairs (0; it throws otherwise) in stats.crossing_pairs.
std::size_t refuse_crossing_faces(const ObjModel& model);

// The three checks in order (bow-ties, duplicates, crossings), as load_and_mesh runs them.
DefectStats check_defects(ObjModel& model);

// The offset subtracted from every position when a model lies far from the origin compared
// with its size (its largest |coordinate| above kRecentreRatio × its bounding-box diagonal):
// the bounding box's centre; (0,0,0) otherwise (nothing changes). Far from the origin, every
// tolerance that grows with |coordinate| (geometry/tolerance.hpp) would otherwise grow with the
// distance instead of the scene's own size. The subtraction is exact (Sterbenz: every coordinate
// is within a factor 2 of the centre's), so the model's geometry is kept bit for bit.
inline constexpr double kRecentreRatio = 1024.0;
Vec3 recentre(ObjModel& model);

}  // namespace ffcube
