// Internal to the accuracy layer. One job: decide soundly whether anything can block a near
// pair (the occlusion, or shaft, test): true only when every other patch whose bounding box
// meets the pair's is separated from the convex hull of the two patches by a plane.
#pragma once

#include <cstdint>
#include <vector>

#include "accuracy/patch_set.hpp"
#include "accuracy/spatial_grid.hpp"

namespace ffcube::accuracy {

// Reused across calls (no heap allocation once grown).
struct ShaftScratch {
    std::vector<Vec3> axes;
    std::vector<std::pair<double, double>> axis_extent;  // the hull's projection on each of axes
    std::vector<Vec3> segments;
    // The last blocker shaft_unoccluded found (a wall beside the sender blocks many of its
    // pairs): the next call tests it first. Only the order of the tests: not the answer.
    std::uint32_t last_blocker = UINT32_MAX;
    // Calls answered by that blocker crossing the segment between the two parts' centres deep
    // inside (no axis can then separate it: shaft_test.cpp, crosses_deep), before any axis.
    std::uint64_t deep_crossings = 0;
};

// Separating-axis test between the convex hull of patches i ∪ j (the parts of each in front of
// the other's plane, see shaft_test.cpp) and each other patch q whose
// bounding box meets the pair's (inflated by the tolerance of touching, 1e-9 of the pair's
// size). Touching counts as separated (contact in a supporting plane of the hull blocks a set of
// segments of measure zero). A missed separating axis can only make the test refuse: it may
// return false for an unoccluded pair, never true for an occluded one.
bool shaft_unoccluded(const PatchSet& patches, const SpatialGrid& grid, std::uint32_t i, std::uint32_t j,
                      ShaftScratch& scratch);

// The same test, collecting every candidate that no axis separates from the hull (the possible
// blockers: a patch not among them cannot meet a segment between i and j). Stops once more than
// `max` are found; returns whether at most `max` were (blockers then sorted, so the caller's use
// of them does not depend on the grid's visiting order).
bool shaft_blockers(const PatchSet& patches, const SpatialGrid& grid, std::uint32_t i, std::uint32_t j,
                    ShaftScratch& scratch, std::vector<std::uint32_t>& blockers, std::size_t max);

}  // namespace ffcube::accuracy
