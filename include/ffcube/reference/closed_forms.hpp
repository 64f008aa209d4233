// Closed-form view factors from J. R. Howell's catalogue, the independent references that the
// bench (`ffcube bench`) and the tests measure ffcube against. Not part of the engine: the
// library computes form factors by hemicubes, rays and polygon contour integrals
// (ffcube/geometry/analytic.hpp), never by these.
//
// Convention: F12 = fraction of the energy leaving surface 1 (diffusely) that arrives at
// surface 2. Case numbers refer to J. R. Howell, "A Catalog of Radiation Heat Transfer
// Configuration Factors" (3rd ed.); B-n cases are from a differential element, C-n between
// finite areas. All lengths in the same (any) unit. Invalid arguments throw InputError.
#pragma once

namespace ffcube {

// ---- Closed forms ------------------------------------------------------------------------

// Howell C-11: two identical, parallel, directly opposed rectangles a × b at distance c.
// With X = a/c, Y = b/c:
//   F = 2/(πXY) { ln √[(1+X²)(1+Y²)/(1+X²+Y²)] + X√(1+Y²) atan(X/√(1+Y²))
//                 + Y√(1+X²) atan(Y/√(1+X²)) − X atan X − Y atan Y }.
// F(1,1,1) = 0.1998244... a, b, c > 0. Evaluated in a regrouped form with no cancellation
// (see the .cpp), so far-apart and thin rectangles keep full precision.
double ff_parallel_rectangles(double a, double b, double c);

// Parallel rectangles with arbitrary offsets (Howell C-12, the superposition formula of
// Gross, Spindler and Hahne 1981 / Ehlert and Smith 1993): rectangle 1 is [x1,x2]×[y1,y2] in
// the plane z = 0, rectangle 2 is [ξ1,ξ2]×[η1,η2] in the plane z = c, facing each other.
//   A1 F12 = 1/(2π) Σ_{i,j,k,l ∈ {1,2}} (−1)^(i+j+k+l) G(x_i − ξ_k, y_j − η_l),
//   G(u,v) = v√(u²+c²) atan(v/√(u²+c²)) + u√(v²+c²) atan(u/√(v²+c²)) − c²/2 ln(u²+v²+c²).
// Requires x1 < x2, y1 < y2, ξ1 < ξ2, η1 < η2, c > 0. Returns F12. The 16 terms are
// O(size² · ln) and cancel to A1 F12: for rectangles far apart (distance D ≫ size L) about
// 2·log10(D/L) digits are lost; ff_polygon_polygon keeps them.
double ff_parallel_rectangles_offset(double x1, double x2, double y1, double y2, double xi1,
                                     double xi2, double eta1, double eta2, double c);

// Howell C-14: rectangles at 90° sharing a common edge of length l; rectangle 1 has width w
// (perpendicular to the edge), rectangle 2 has height h. With H = h/l, W = w/l:
//   F12 = 1/(πW) { W atan(1/W) + H atan(1/H) − √(H²+W²) atan(1/√(H²+W²))
//        + ¼ ln[ (1+W²)(1+H²)/(1+W²+H²) · (W²(1+W²+H²)/((1+W²)(W²+H²)))^(W²)
//                                       · (H²(1+H²+W²)/((1+H²)(H²+W²)))^(H²) ] }.
// F(1,1,1) = 0.2000438... l, w, h > 0. Thin plates lose a few digits to cancellation in
// the bracket (1e-13 relative at W = 1e-4, against the contour integral).
double ff_perpendicular_rectangles_common_edge(double l, double w, double h);

// Howell C-41: coaxial parallel disks, radius r1 (from) and r2 (to), distance h apart.
// With R1 = r1/h, R2 = r2/h, X = 1 + (1+R2²)/R1²:  F12 = ½ [X − √(X² − 4 (R2/R1)²)].
double ff_coaxial_disks(double r1, double r2, double h);

// Differential element to a parallel rectangle a × b at distance c, one corner of the
// rectangle on the element's normal (Howell B-1 (corner form)). With A = a/c, B = b/c:
//   F = 1/(2π) [ A/√(1+A²) atan(B/√(1+A²)) + B/√(1+B²) atan(A/√(1+B²)) ].
double ff_diff_parallel_rect(double a, double b, double c);

// Differential element to a perpendicular rectangle (Howell B-3): the rectangle stands on the
// element's plane (its bottom edge lies in that plane), it is `width` wide along that edge and
// `height` tall, its plane is at distance c from the element, and the element lies on the
// perpendicular to the rectangle's plane through one end of the bottom edge. With
// W = width/c, H = height/c:   F = 1/(2π) [ atan W − atan(W/√(1+H²)) / √(1+H²) ].
// (Howell writes it as 1/(2π)[atan(1/Y) − Y/√(X²+Y²) atan(1/√(X²+Y²))], X = height/width,
// Y = c/width: the same function.)
double ff_diff_perpendicular_rect(double width, double height, double c);

// Concentric spheres, inner radius r1, outer r2 ≥ r1 (Howell C-136 is the general case).
struct SphereFactors {
    double f12;  // inner → outer: 1
    double f21;  // outer → inner: (r1/r2)²
    double f22;  // outer → itself: 1 − (r1/r2)²
};
SphereFactors ff_concentric_spheres(double r1, double r2);

}  // namespace ffcube
