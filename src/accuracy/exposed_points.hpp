// The accuracy layer's sender rule for a sender cut by a facet (issue 14, generated cities: the ground
// grid's triangles run on under buildings). A row measured by sub-hemicubes puts its points on
// the sender by a fixed rule; a point that falls inside a building sees the building's back
// faces, which says nothing about the exposed part of the sender. For such a sender the points
// go on the exposed part only, with weights that integrate polynomials of degree ≤ 2 over it
// exactly (docs/accuracy.md, "Senders cut by a facet").
//
// The enclosed part of the sender counts as sky: it adds nothing to Σ_j F_ij, so 1 − Σ_j F_ij
// (the sky view factor) includes it, as it did when its points saw back faces only.
#pragma once

#include <array>
#include <cstdint>
#include <memory>
#include <span>
#include <vector>

#include "ffcube/raycast/ray_scene.hpp"
#include "ffcube/scene/scene.hpp"

namespace ffcube {

namespace accuracy {
struct PatchSet;
class SpatialGrid;
}  // namespace accuracy

// A region of a plane as the union of polygons (local 2D coordinates): its moments
// ∫ 1, x, y, x², xy, y² dA, exact (Green's theorem on each polygon, counter-clockwise).
using Moments = std::array<double, 6>;
Moments polygon_moments(std::span<const std::array<double, 2>> poly);
// The six monomials at (x, y), in the order of Moments.
Moments monomials(double x, double y);

// Weights for the points (x, y) that reproduce `target` (moments), closest to w0 in the least-
// squares sense: w = w0 + Aᵀ(AAᵀ)⁻¹(target − A w0), A the monomials at the points. False (w left
// as w0) when the points do not determine a quadratic (fewer than 6, or on a conic).
bool fit_weights(std::span<const std::array<double, 2>> points, const Moments& target, std::vector<double>& w);

class ExposedPoints {
public:
    // The scene must outlive this. Builds the patch boxes' grid and the ray scene (O(n log n)).
    explicit ExposedPoints(const Scene& scene);
    ~ExposedPoints();

    // Whether a facet crosses the interior of patch i: some patch rises in front of i's plane and
    // meets that plane along a segment that passes strictly inside i (not only along its edges),
    // or a cover lies just in front of part of i (accuracy::covers_part: a light below a ceiling).
    bool cut(std::uint32_t i) const;

    // For a cut patch i with some part enclosed: the points on its exposed part and their
    // weights (Σ = exposed area / area of i), and true. False (points untouched) when i is not
    // cut or no cell of it is enclosed: the caller keeps its own rule.
    bool rule(std::uint32_t i, std::vector<Vec3>& points, std::vector<double>& weights) const;

    static constexpr int kCells = 32;   // the cell grid over the sender's bounding rectangle
    static constexpr int kPoints = 16;  // sender points on the exposed part (4 × 4 strata)
    // A cell is enclosed when its normal ray and four rays kTiltDegrees off it all meet back faces.
    static constexpr double kTiltDegrees = 60.0;

private:
    struct Cell {
        std::array<double, 2> c;  // centroid of the cell within the patch (local coordinates)
        double area;
        Moments m;
    };
    bool enclosed(std::uint32_t i, const Vec3& at) const;
    void choose_points(std::vector<Cell>& cells, std::vector<std::size_t>& chosen, std::vector<double>& w0) const;

    const Scene& scene_;
    std::unique_ptr<accuracy::PatchSet> patches_;
    std::unique_ptr<accuracy::SpatialGrid> grid_;
    RayScene rays_;
};

}  // namespace ffcube
