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

#include <array>
#include <cstdint>
#include <vector>

#include "accuracy/patch_set.hpp"
#include "accuracy/spatial_grid.hpp"

namespace ffcube::accuracy {

// A cover of patch i: a patch q that lies wholly in front of i's plane, close to it (every vertex
// at most kCoverGap × i's size in front), shows i its back (i's centroid behind q's plane), and
// whose outline, projected along i's normal onto i's plane, crosses i's interior. The part of i
// under q sees q's back only; the rest sees the scene: i's centre does not see what i sees on
// average (the Cornell box's light hangs 0.1 below the ceiling: a ceiling patch whose centroid
// lies above the light's edge had an empty row, its exposed part seeing the room; docs/accuracy.md,
// "Senders partly covered"). Such a sender is measured as one cut by a facet
// (gl/exposed_points.hpp: points on its exposed part only).
// kCoverGap: ExposedPoints counts a point as enclosed when its normal ray and rays 60° off it all
// meet back faces, i.e. when it lies at least g·tan 60° = 1.73 g inside q's outline (g the gap);
// the deepest point under q lies at most one size of i inside it, so for g > size/1.73 = 0.58 size
// no point can count as enclosed and the exposed-point rule has nothing to leave out: 0.5.
inline constexpr double kCoverGap = 0.5;

// Whether segment a → b passes through the interior of the convex polygon `poly` (2D, counter-
// clockwise) shrunk by `margin`, over a length of more than `margin` (Cyrus–Beck). Shared with
// gl/exposed_points.cpp (enclosed cells).
bool segment_inside(const std::vector<std::array<double, 2>>& poly, const std::array<double, 2>& a,
                    const std::array<double, 2>& b, double margin);
bool covers_part(const PatchSet& patches, std::uint32_t i, std::uint32_t q);

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
    // sweeps across the sender. Also 2: a cover of i (covers_part), which hides part of the
    // sender from everything. near: the caller's scratch.
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
