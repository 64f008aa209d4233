// Exact form factors past a few convex occluders (issue 14/15: near pairs that the shaft test
// cannot prove unoccluded, e.g. a large wall beside a re-entrant corner). Pure math, no GL.
//
// Point kernel: from a point p with unit normal n, the factor to the part of a convex receiver R
// that p sees past convex occluders O_1..O_k. Each occluder is first clipped to the slab between
// R's plane and p's level above it (only that part can meet a segment from p to R); the cone from
// p over the clipped occluder is the intersection of the half-spaces bounded by the planes through
// p and each of its edges, and R is split successively into convex pieces outside each cone (a
// piece is cut by the cone's planes one after the other: the part outside plane 1, the part inside
// 1 but outside 2, …; the part inside all is shadow and dropped). No projection onto R's plane is
// made, so occluders close to p's level do not send points to infinity. The factor is Lambert's
// contour sum (ff_point_polygon) over the visible pieces, each clipped to p's front half-space.
//
// Area kernel: that point factor integrated over a convex sender S by a globally adaptive rule:
// S is fan-triangulated; each triangle's integral is a collapsed (Duffy) 4 × 4 Gauss rule, its
// error estimate |rule(T) − Σ rule(children)| (children: the 4 midpoint triangles, whose values
// replace the parent's); the triangle with the largest estimate is split until the sum of the
// estimates is below the tolerance or the point budget is spent. Visibility makes the integrand
// kinked where a shadow edge sweeps over a corner of R, which a fixed rule would follow only at
// first or second order; the adaptive rule puts its points there. Deterministic: the order of
// splits depends on the input only.
#pragma once

#include <cstdint>
#include <span>
#include <vector>

#include "ffcube/geometry/polygon.hpp"

namespace ffcube {

// Whether a planar polygon is convex (every turn the same way about its Newell normal, collinear
// vertices allowed). The kernels below require convex receivers, occluders and senders.
bool polygon_is_convex(std::span<const Vec3> poly);

// F from the point p (unit normal n) to the part of the convex polygon `receiver` visible past the
// convex `occluders`. 0 when p is not in front of the receiver's plane (one-sided, as the point
// kernel of a sender facing it). With no occluders it equals ff_point_polygon(p, n, receiver).
// pieces_out (optional): how many visible convex pieces were summed.
double ff_point_visible_polygon(const Vec3& p, const Vec3& n, std::span<const Vec3> receiver,
                                std::span<const std::vector<Vec3>> occluders, std::size_t* pieces_out = nullptr);

struct VisibleFFOptions {
    double tolerance = 1e-8;          // absolute, on F (Σ of the triangles' error estimates / A_S)
    std::uint64_t max_points = 60000;  // point-kernel evaluations at most (then: not converged)
    int min_depth = 2;  // each fan triangle is split this many times (4^d cells) before adapting
};

struct VisibleFFResult {
    double f = 0;            // F(sender → visible part of receiver), per unit sender area
    double error = 0;        // Σ of the error estimates / A_S (a bound in practice: see the test)
    std::uint64_t points = 0;  // point-kernel evaluations
    bool converged = false;  // error ≤ tolerance within max_points
};

// The point-kernel evaluations ff_polygon_visible_polygon makes at least on a sender of this many
// vertices, before any adaptive split: (vertices − 2) fan triangles, each split min_depth times,
// each cell's rule and its 4 children's (5 × 16 points). Each split adds 4 × 16.
std::uint64_t visible_ff_min_points(std::size_t sender_vertices, const VisibleFFOptions& options = {});

// F(S → R past the occluders) = 1/A_S ∫_S F_point(p) dA. The sender's normal is its Newell
// normal; its area A_S is the whole polygon's (pass the part of S in front of R's plane if the rest
// should count 0 without adding a kink: it does count 0 either way).
VisibleFFResult ff_polygon_visible_polygon(std::span<const Vec3> sender, std::span<const Vec3> receiver,
                                           std::span<const std::vector<Vec3>> occluders,
                                           const VisibleFFOptions& options = {});

}  // namespace ffcube
