// Analytic (exact) form factors between polygons, which the near-field correction and the far
// field evaluate. Pure math in double precision, no occlusion. The closed forms of Howell's
// catalogue, which only the bench and the tests use, are in ffcube/reference/closed_forms.hpp.
//
// Convention everywhere: F12 = fraction of the energy leaving surface 1 (diffusely) that
// arrives at surface 2, F12 = 1/A1 ∫∫ cosθ1 cosθ2 / (π r²) dA2 dA1; reciprocity A1 F12 = A2 F21.
// Case numbers refer to J. R. Howell, "A Catalog of Radiation Heat Transfer Configuration
// Factors" (3rd ed., http://www.thermalradiation.net/indexCat.html); B-n cases are from a
// differential element, C-n cases between finite areas. All lengths in the same (any) unit.
#pragma once

#include "ffcube/core/stats.hpp"
#include "ffcube/geometry/polygon.hpp"

#include <cstdint>
#include <span>

namespace ffcube {

// ---- Polygons ----------------------------------------------------------------------------
// Polygons are planar: up to rounding (geometric_tolerance(1e-9, size, max |coordinate|): 1e-9
// of the polygon's size, or the rounding of its coordinates far from the origin,
// geometry/tolerance.hpp) they are used as given; up to kPlanarityTolerance (1e-6) of their size,
// what the mesher calls planar, they are projected onto their Newell plane through their
// centroid first (counted in AnalyticStats::flattened_polygons; F moves by about that relative
// amount); beyond, InputError. They have ≥ 3 vertices and non-zero area, may be non-convex but
// not self-intersecting, and are counter-clockwise seen from their front (polygon.hpp).

// Differential area at p with unit normal n to a polygon: Lambert's contour formula,
//   F = 1/(2π) Σ_k β_k (n · γ̂_k),  γ̂_k = unit(r_{k+1} × r_k), β_k = angle(r_k, r_{k+1}),
// r_k = v_k − p. The part of the polygon behind p's plane is first clipped away
// (Sutherland–Hodgman) because it cannot receive; without the clip the formula would count it
// negatively. The value does not depend on which side of the polygon faces p (F is the
// projected solid angle fraction; one-sidedness is the caller's affair). A point in the
// polygon's plane (to geometric_tolerance(1e-12, size, max |coordinate|)), its boundary
// included, sees it edge-on: 0.
double ff_point_polygon(const Vec3& p, const Vec3& n, std::span<const Vec3> poly);

// The same for the common case in inner loops, without checks or clipping: the caller knows
// that n is a unit vector and that every vertex of poly lies strictly in front of p's plane (so
// nothing needs clipping). Returns the same value as ff_point_polygon there (test
// PointPolygonFastPathAgrees), at a fraction of the cost.
double ff_point_polygon_unclipped(const Vec3& p, const Vec3& unit_n, std::span<const Vec3> poly);

// Polygon 1 to polygon 2, no occlusion, front sides only: the parts of each polygon behind the
// other's plane are clipped away first (the integrand is zero there unless counted with the
// wrong sign), then Stokes' theorem turns the area integrals into the double contour integral
//   A1 F12 = 1/(2π) ∮_{C1} ∮_{C2} ln r  dx1 · dx2
// (Sparrow 1963). Per pair of edges: parallel edges (collinear or not) use the exact closed
// form of ∫∫ ½ ln((s−t)²+h²) ds dt; other pairs integrate ln r along edge 1 in closed form
// and along edge 2 by adaptive Gauss–Kronrod (7/15) split at the point of edge 2 closest to
// edge 1, where the log singularity or near-singularity is. So shared edges, shared vertices
// and near-touching polygons (gap 1e-3 or less) stay exact to ~1e-12 relative.
// Coordinates are shifted to polygon 1's centroid and scaled by the size of the pair first, so
// offsets of 1e5 and scales of 1e-4 or 1e4 give the same F. Vertices within
// geometric_tolerance(1e-12, 1, max |coordinate| / size) of the other polygon's plane count as
// on it (not clipped), and a polygon whose front part lies within that of the other's plane
// sees it edge-on: 0.
// Far apart (bounding spheres separated by at least 2 radii of the smaller polygon) the
// contour integral's O(L² ln D) terms would cancel to O(L⁴/D²) and lose 2·log10(D/L) digits;
// there F is instead Lambert's formula integrated over the smaller polygon (reciprocity) by a
// 20×20 Gauss rule through Green's theorem. Lambert's terms are O(L/D) and F is O((L/D)²)
// for surfaces facing each other (1e-15 relative at D/L = 1e3) down to O((L/D)³) for surfaces
// seen edge-on (1e-10 relative at D/L = 1e3).
// Returns 0 when nothing of one polygon is in front of the other.
// Bounded work (docs/robustness.md): every call evaluates at most
// ff_polygon_polygon_budget(k1, k2) integrands, k1, k2 the vertex counts after clipping (≤ n + 1
// for a convex n-gon, ≤ 2n in general); see AnalyticCallInfo for what one call did.
double ff_polygon_polygon(std::span<const Vec3> p1, std::span<const Vec3> p2);

// ---- Work bounds and accounting ----------------------------------------------------------
// The contour integral's quadrature, per pair of edges: adaptive Gauss–Kronrod 7/15 bisects a
// cut of edge 2 (≤ 4 cuts) only while a panel is wider than 4ε of the edge (so ≤ 50 levels) and
// its |K15 − G7| exceeds its tolerance, the integrand's rounding and 50ε of its magnitude. With
// the singularities at cut ends, at most 2 panels per level are split (one at each end), so
// ≤ 4 evaluated: ≤ 4 cuts × 50 levels × 4 panels × 15 = 12,000 evaluations, the split budget. Once it is spent nothing more is split:
// each panel then evaluated or pending (≤ 50 on the stack + 3 cuts + the graded cuts) keeps its
// K15 value — the fallback, counted with |K15 − G7| as its error bound — so a pair never exceeds
// kContourEvalsPerEdgePair evaluations (an evaluation: ∫ ln r along edge 1 in closed form).
// Graded cuts: where edge 2 passes near edge 1 or its ends without touching, at most
// kMaxGradedCutsPerSide cuts on each side of each of the 3 cuts, at distances ρ 4^k
// (analytic.cpp, edge_pair: from ρ > 4ε of edge 2 to an eighth of it, ≤ 24 factors of 4).
inline constexpr int kMaxQuadDepth = 50;
inline constexpr int kMaxGradedCutsPerSide = 28;
inline constexpr std::uint64_t kEdgePairSplitBudget = 4 * 50 * 4 * 15;
inline constexpr std::uint64_t kContourEvalsPerEdgePair =
    kEdgePairSplitBudget + 15 * (kMaxQuadDepth + 3 + 6 * kMaxGradedCutsPerSide);
// The far-field rule (fixed 20 × 20 Gauss points per edge of the smaller polygon, each one
// Lambert sum over the other polygon): no adaptivity, no fallback.
inline constexpr std::uint64_t kFarFieldEvalsPerEdge = 400;
// The most integrand evaluations one ff_polygon_polygon call may make, given the vertex counts
// k1, k2 of the clipped polygons: max(k1 k2 kContourEvalsPerEdgePair, max(k1, k2) kFarField…).
std::uint64_t ff_polygon_polygon_budget(std::size_t k1, std::size_t k2);

// What one ff_polygon_polygon call did (the optional out-parameter overload below).
struct AnalyticCallInfo {
    enum class Method { zero, contour, far_field };
    Method method = Method::zero;      // zero: nothing in front / edge-on, no integral evaluated
    std::size_t clipped_vertices1 = 0;  // vertex counts after clipping (0 when not clipped)
    std::size_t clipped_vertices2 = 0;
    std::uint64_t evaluations = 0;  // integrand evaluations (ln-r edge integrals or Lambert sums)
    std::uint64_t budget = 0;       // ff_polygon_polygon_budget(clipped counts): evaluations ≤ budget
    std::uint64_t fallbacks = 0;    // quadrature panels accepted unconverged (budget or depth spent)
    double error_bound = 0.0;       // bound on |F12 error| from those panels (0 when none)
};
// The same value as ff_polygon_polygon(p1, p2), with its work reported in `info`.
double ff_polygon_polygon(std::span<const Vec3> p1, std::span<const Vec3> p2, AnalyticCallInfo& info);

// Process-wide totals of ff_polygon_polygon calls since the last reset, a statistics set
// (core/stats.hpp: each declared once, merged, flattened and reported by its key). Any thread may
// call; each call merges its figures under a lock, so totals are exact and reads a snapshot. For
// the run report: "analytic fallbacks: N" = fallback_calls.
#define FFCUBE_ANALYTIC_STATS(X)                                                                              \
    X(std::uint64_t, calls, sum, "analytic.calls")                                                            \
    X(std::uint64_t, evaluations, sum, "analytic.evaluations")                                                \
    X(std::uint64_t, max_evaluations_per_call, max, "analytic.max_evaluations_per_call")                      \
    X(std::uint64_t, fallbacks, sum, "analytic.fallbacks")           /* panels accepted unconverged */        \
    X(std::uint64_t, fallback_calls, sum, "analytic.fallback_calls") /* calls with such a panel */            \
    X(std::uint64_t, flattened_polygons, sum, "analytic.flattened_polygons") /* projected onto their plane */
struct AnalyticStats {
    FFCUBE_STATS(AnalyticStats, FFCUBE_ANALYTIC_STATS)
};
AnalyticStats analytic_stats();
void reset_analytic_stats();
// Adds another process's totals (an MPI rank's) to this process's.
void merge_analytic_stats(const AnalyticStats& other);

// Monte Carlo reference for tests: `samples` points uniform on polygon 1 (convex polygons only:
// fan triangulation), each shooting one cosine-distributed ray from its front; F12 = fraction
// of rays that hit polygon 2's front (the side ff_polygon_polygon counts; no occlusion).
// Binomial, so the standard error is √(F(1−F)/n).
// Deterministic for a given seed (mt19937_64, own real conversion).
double ff_polygon_polygon_mc(std::span<const Vec3> p1, std::span<const Vec3> p2,
                             std::uint64_t samples, std::uint64_t seed);

}  // namespace ffcube
