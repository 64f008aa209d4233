// Internal to the accuracy layer. One job: deciding, from the geometry alone, whether what a
// sender sees may change across it because an occluder stands close to it (issue 14: ground
// cells beside a wall), so that its row is measured by sub-hemicubes at its quadrature points
// instead of one hemicube at its centre.
//
// Why: a hemicube sees from the sender's centre. The sender quadrature (sender_quadrature.hpp)
// corrects that for unoccluded pairs, but it scales the visible part by an unoccluded ratio:
// where an occluder's silhouette moves across the sender (an occluder within a few sender sizes),
// the centre's visibility is not the sender's average visibility, and the error is one-signed over
// whole rows of cells along a wall (docs/accuracy.md, "Senders beside an occluder").
#pragma once

#include <cstdint>
#include <vector>

#include "accuracy/patch_set.hpp"
#include "accuracy/spatial_grid.hpp"

namespace ffcube::accuracy {

class SenderVisibility {
public:
    // k: the near distance in sizes (NearFieldOptions::k).
    SenderVisibility(const PatchSet& patches, const SpatialGrid& grid, double k);

    // An occluder of i is a patch q near i (centroids closer than k × the larger size) that rises
    // in front of i's plane (a vertex farther than plane_tolerance in front of it), facing i (i's
    // centre not behind q's plane: a block's walls seen from under it hide nothing), with something
    // possibly behind it as seen from i: the scene's bounding box reaches strictly beyond q's
    // plane on the side away from i's centroid. An occluder with nothing behind it (the walls of a
    // closed room, the ground under a wall) hides nothing and does not count.
    // Returns 0: no occluder; 1: an occluder; 2: an occluder touching i, its bounding box closer
    // to i's centroid than i's size (a wall rising from the sender's edge), whose silhouette
    // sweeps across the sender. near: the caller's scratch.
    int occluder_level(std::uint32_t i, std::vector<std::uint32_t>& near) const;
    // The same from `near` already holding the grid's candidates for i's reach (k × the larger of
    // i's size and the largest patch's, as the near-pair search queries it): no second query.
    int occluder_level_of_candidates(std::uint32_t i, const std::vector<std::uint32_t>& near) const;

private:
    const PatchSet& patches_;
    const SpatialGrid& grid_;
    double k_;
    Box scene_box_;
};

}  // namespace ffcube::accuracy
