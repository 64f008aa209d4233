#include "ffcube/geometry/analytic.hpp"

#include "ffcube/geometry/quadrature.hpp"
#include "ffcube/geometry/tolerance.hpp"

#include "ffcube/core/error.hpp"

#include <fmt/format.h>
#include <glm/geometric.hpp>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <mutex>
#include <numbers>
#include <random>
#include <vector>

namespace ffcube {

namespace {

// The process's AnalyticStats (analytic_stats()): each call's figures merged under the lock.
std::mutex g_stats_mutex;
AnalyticStats g_stats;

void add_stats(const AnalyticStats& s) {
    const std::lock_guard lock(g_stats_mutex);
    stats::merge(g_stats, s);
}

constexpr double kPi = std::numbers::pi;

// ---- polygon checks and clipping ---------------------------------------------------------

// Validates a polygon and returns it as the kernels use it. Planar up to rounding (1e-9 of its
// size, or the rounding of its coordinates far from the origin: a planar polygon 2.8e-4 wide at
// 1e5 is 7e-12 = 2.6e-8 of its size off its plane by rounding alone): the polygon itself,
// untouched. Off its plane by up to kPlanarityTolerance of its size (what the mesher calls planar,
// so its patches of such a face come here; a UV sphere written with 6 decimals has quads 1e-7 of
// their size off): projected onto its Newell plane through its centroid, in `storage`. The
// value is then that of the projected polygon; a vertex moves by at most 1e-6 of the size, which
// changes F by about as much relative (docs/accuracy.md), far below every other error. Beyond:
// InputError naming the rule.
std::span<const Vec3> planar_polygon(const char* fn, const char* which, std::span<const Vec3> poly,
                                     std::vector<Vec3>& storage) {
    if (poly.size() < 3)
        throw InputError(fmt::format("{}: {} has {} vertices; a polygon needs at least 3", fn,
                                     which, poly.size()));
    for (const Vec3& v : poly)
        if (!std::isfinite(v.x) || !std::isfinite(v.y) || !std::isfinite(v.z))
            throw InputError(fmt::format("{}: {} has a NaN or infinite coordinate", fn, which));
    const double size = polygon_max_edge(poly);
    if (!(polygon_area(poly) > 0.0) || !(size > 0.0))
        throw InputError(fmt::format("{}: {} has zero area", fn, which));
    const double deviation = polygon_planarity_deviation(poly);
    const double coord = max_abs_coordinate(poly);
    if (deviation <= geometric_tolerance(1e-9, size, coord)) return poly;
    const double allowed = geometric_tolerance(kPlanarityTolerance, size, coord);
    if (deviation > allowed)
        throw InputError(fmt::format("{}: {} is not planar (a vertex is {:.3g} off its plane, "
                                     "more than {:.3g}: {:g} of its size {:.3g}, or the rounding "
                                     "of its coordinates if larger)",
                                     fn, which, deviation, allowed, kPlanarityTolerance, size));
    const Vec3 n = polygon_normal(poly), c = polygon_centroid(poly);
    storage.assign(poly.begin(), poly.end());
    for (Vec3& v : storage) v -= glm::dot(v - c, n) * n;
    AnalyticStats flattened;  // a polygon projected onto its plane
    flattened.flattened_polygons = 1;
    add_stats(flattened);
    return storage;
}

// Sutherland–Hodgman against one plane: keeps the part of `in` where dot(v − o, m) ≥ 0.
// Vertices on the plane are kept, so a polygon touching the plane along an edge keeps it. A
// vertex within `on_plane` of the plane counts as on it (geometric_tolerance: the plane and the
// vertex are known only to rounding). Without that, a shared hinge edge whose two ends round to
// ±1e-15 of the other plane was cut at its midpoint, and the cut ran along the polygon for
// 1e-15 / sin α of its length: at a fold angle α of 1e-6 a sliver 1e-9 wide next to the hinge,
// where the kernel is strongest, was lost (A1 F12 off by 6e-9 relative, and reciprocity too).
void clip_to_front(std::span<const Vec3> in, const Vec3& o, const Vec3& m, std::vector<Vec3>& out,
                   double on_plane = 0.0) {
    out.clear();
    const std::size_t k = in.size();
    const auto side = [&](const Vec3& v) {
        const double d = glm::dot(v - o, m);
        return std::abs(d) <= on_plane ? 0.0 : d;
    };
    for (std::size_t i = 0; i < k; ++i) {
        const Vec3& a = in[i];
        const Vec3& b = in[(i + 1) % k];
        const double da = side(a), db = side(b);
        if (da >= 0.0) out.push_back(a);
        if ((da > 0.0 && db < 0.0) || (da < 0.0 && db > 0.0))
            out.push_back(a + (da / (da - db)) * (b - a));
    }
}

// ---- Lambert's contour formula -----------------------------------------------------------

// Σ β_k n·γ̂_k with γ̂_k = unit(r_{k+1} × r_k): positive when the polygon's front faces p.
// p must be off the polygon's plane, so no r_k is zero and no edge is collinear with p.
double lambert_sum(const Vec3& p, const Vec3& n, std::span<const Vec3> poly) {
    const std::size_t k = poly.size();
    double sum = 0.0;
    for (std::size_t i = 0; i < k; ++i) {
        const Vec3 a = poly[i] - p, b = poly[(i + 1) % k] - p;
        const Vec3 c = glm::cross(b, a);
        const double sc = glm::length(c);
        if (sc > 0.0) sum += std::atan2(sc, glm::dot(a, b)) * glm::dot(n, c) / sc;
    }
    return sum;
}

// ---- ln r on pairs of segments -----------------------------------------------------------

// ∫ ½ ln(u² + h²) du = ½ u ln(u²+h²) − u + h atan(u/h), h ≥ 0; continuous at h = 0 and u = 0.
double log_primitive(double u, double h) {
    const double r2 = u * u + h * h;
    const double log_term = r2 > 0.0 ? 0.5 * u * std::log(r2) : 0.0;
    const double atan_term = h > 0.0 ? h * std::atan(u / h) : 0.0;
    return log_term - u + atan_term;
}

// Φ with Φ'' = ½ ln(x² + h²): Φ(x) = ¼(x² − h²) ln(x²+h²) − ¾x² + h x atan(x/h).
double log_second_primitive(double x, double h) {
    const double r2 = x * x + h * h;
    const double log_term = r2 > 0.0 ? 0.25 * (x * x - h * h) * std::log(r2) : 0.0;
    const double atan_term = h > 0.0 ? h * x * std::atan(x / h) : 0.0;
    return log_term - 0.75 * x * x + atan_term;
}

// QUADPACK qk15 nodes (Kronrod) and weights; the 7-point Gauss rule uses the odd nodes.
constexpr std::array<double, 8> kXgk = {
    0.991455371120812639206854697526329, 0.949107912342758524526189684047851,
    0.864864423359769072789712788640926, 0.741531185599394439863864773280788,
    0.586087235467691130294144845693013, 0.405845151377397166906606412076961,
    0.207784955007898467600689403773245, 0.0};
constexpr std::array<double, 8> kWgk = {
    0.022935322010529224963732008058970, 0.063092092629978553290700663189204,
    0.104790010322250183839876322541518, 0.140653259715525918745189590510238,
    0.169004726639267902826583426598550, 0.190350578064785409913256402421014,
    0.204432940075298892414161999234649, 0.209482141084727828012999174891714};
constexpr std::array<double, 4> kWg = {
    0.129484966168869693270611432679082, 0.279705391489276667901467771423780,
    0.381830050505118944950369775488975, 0.417959183673469387755102040816327};

// Work of the adaptive quadrature of one edge pair, and what was left unconverged.
struct QuadWork {
    std::uint64_t evaluations = 0;
    std::uint64_t fallbacks = 0;  // panels accepted unconverged (budget or depth spent)
    double fallback_error = 0.0;  // Σ |K15 − G7| over those panels: a bound on their error
};

// Adaptive Gauss–Kronrod on [a,b]: bisect until |K15 − G7| ≤ tol (halved per level). The log
// singularities here sit at interval ends (the callers split there), where bisection converges
// geometrically: at most 2 panels per level. Every panel is accepted, whatever its tolerance, when
//  - |K − G| ≤ noise × (b − a): the integrand's absolute rounding (the caller's estimate), or
//  - |K − G| ≤ 50 ε × resabs (resabs = ∫|f| by the same rule; QUADPACK's roundoff test): the
//    difference is then rounding of the values themselves, relative to their magnitude, or
//  - b − a ≤ min_width = 4 ε × (the edge's length): the panel is below the resolution of the
//    edge's points. The integrand is bounded (g is continuous), so such a panel holds less than
//    the rounding of the edge's whole integral. Cuts are at most one edge long, so this alone
//    stops every branch by depth log2(1/(4ε)) = 50 = kMaxQuadDepth.
// So no bisection relies on rounding noise to stop. Two more stops count as fallbacks (the
// panel keeps its K15 value and |K − G| is added to the error bound): depth 0, and the
// evaluation budget `limit` spent (panels still on the stack are then integrated by K15 once
// each, unsplit: the fixed rule on what remains).
template <class F>
double integrate(const F& f, double a, double b, double tol, double noise, double min_width, int depth,
                 std::uint64_t limit, QuadWork& work) {
    const double c = 0.5 * (a + b), hl = 0.5 * (b - a);
    const double fc = f(c);
    double k = kWgk[7] * fc, g = kWg[3] * fc, resabs = kWgk[7] * std::abs(fc);
    for (int i = 0; i < 7; ++i) {
        const double dx = hl * kXgk[i];
        const double f1 = f(c - dx), f2 = f(c + dx);
        k += kWgk[i] * (f1 + f2);
        resabs += kWgk[i] * (std::abs(f1) + std::abs(f2));
        if (i % 2 == 1) g += kWg[i / 2] * (f1 + f2);
    }
    work.evaluations += 15;
    k *= hl;
    g *= hl;
    resabs *= std::abs(hl);
    FFCUBE_CHECK_MSG(std::isfinite(k), "non-finite integrand in the contour integral");
    constexpr double eps = std::numeric_limits<double>::epsilon();
    const double err = std::abs(k - g);
    // 'noise' is the integrand's absolute rounding error: |K − G| below noise × (b − a) cannot be
    // told from rounding, and bisecting further would split noise in both halves at every level
    // (2^depth evaluations: a sliver clipped 1e-16 thick by an ulp of rounding did exactly that).
    if (err <= std::max({tol, noise * (b - a), 50.0 * eps * resabs})) return k;
    if (b - a <= min_width) return k;
    if (depth == 0 || work.evaluations >= limit) {
        ++work.fallbacks;
        work.fallback_error += err;
        return k;
    }
    return integrate(f, a, c, 0.5 * tol, noise, min_width, depth - 1, limit, work) +
           integrate(f, c, b, 0.5 * tol, noise, min_width, depth - 1, limit, work);
}

// Parameter t ∈ [0, lq] of the point of segment q0 + t e closest to the segment p0 + s d,
// s ∈ [0, lp] (Ericson, Real-Time Collision Detection, 5.1.9; d, e unit, not parallel).
double closest_on_q(const Vec3& p0, const Vec3& d, double lp, const Vec3& q0, const Vec3& e,
                    double lq) {
    const Vec3 r = p0 - q0;
    const double b = glm::dot(d, e), c = glm::dot(d, r), f = glm::dot(e, r);
    // sin² of the angle. 1 − b² cancels for nearly parallel edges (b rounds to 1 below an angle
    // of 1e-8, and the division then gave NaN cuts that silently dropped parts of the integral):
    // there |d × e|² is used, which keeps its relative precision.
    double denom = 1.0 - b * b;
    if (denom < 1e-8) denom = glm::dot(glm::cross(d, e), glm::cross(d, e));
    const double s = denom > 0.0 ? std::clamp((b * f - c) / denom, 0.0, lp) : 0.0;
    const double t = b * s + f;
    // Ericson then re-clamps s for a clamped t; t itself is final, and only t is needed. Any
    // finite t is a valid cut (cuts only speed up the quadrature), so a non-finite one is
    // replaced by the point nearest p0.
    return std::isfinite(t) ? std::clamp(t, 0.0, lq) : std::clamp(f, 0.0, lq);
}

// ∫_{edge P} ∫_{edge Q} ln|x1 − x2| dx1 · dx2 for P = p0→p1, Q = q0→q1.
double edge_pair(const Vec3& p0, const Vec3& p1, const Vec3& q0, const Vec3& q1, QuadWork& work) {
    const Vec3 dp = p1 - p0, dq = q1 - q0;
    const double lp = glm::length(dp), lq = glm::length(dq);
    if (lp == 0.0 || lq == 0.0) return 0.0;
    const Vec3 d = dp / lp, e = dq / lq;
    const double cos_angle = glm::dot(d, e);
    // Perpendicular edges: dx1·dx2 = 0. 1e-15 × the O(lp·lq) integral is below rounding.
    if (std::abs(cos_angle) < 1e-15) return 0.0;
    const double sin_angle = glm::length(glm::cross(d, e));
    if (sin_angle < 1e-12) {
        // Parallel (collinear or not): closed form. Positions of Q's ends along d measured from
        // p0; h = distance between the lines (taken at Q's midpoint; for edges parallel to
        // 1e-12 that moves the ends by at most 1e-12 of the edge).
        const double ta = glm::dot(q0 - p0, d), tb = glm::dot(q1 - p0, d);
        const double t0 = std::min(ta, tb), t1 = std::max(ta, tb);
        const double h = glm::length(glm::cross(0.5 * (q0 + q1) - p0, d));
        const double integral = -((log_second_primitive(lp - t1, h) - log_second_primitive(lp - t0, h)) -
                                  (log_second_primitive(-t1, h) - log_second_primitive(-t0, h)));
        return cos_angle * integral;
    }
    // g(t) = ∫_0^lp ln|p0 + s d − q(t)| ds in closed form; then t by quadrature.
    const auto g = [&](double t) {
        const Vec3 w = p0 - (q0 + t * e);
        const double b = glm::dot(w, d);
        const double h = glm::length(glm::cross(w, d));
        return log_primitive(b + lp, h) - log_primitive(b, h);
    };
    // g is smooth except where q(t) meets segment P, and steep where q(t) passes near P or near
    // its ends: split at the closest approach to P and at the points nearest p0 and p1.
    const double t_near = closest_on_q(p0, d, lp, q0, e, lq);
    const double t_p0 = std::clamp(glm::dot(p0 - q0, e), 0.0, lq);
    const double t_p1 = std::clamp(glm::dot(p1 - q0, e), 0.0, lq);
    FFCUBE_CHECK_MSG(std::isfinite(t_near) && std::isfinite(t_p0) && std::isfinite(t_p1),
                     "contour integral: a non-finite cut would drop part of the edge");
    // Absolute tolerance 1e-13 of the pair's scale lp·lq: the sum over all pairs of a polygon
    // pair then carries ≲ 1e-13 × perimeter1 × perimeter2 of quadrature error.
    const double tol = 1e-13 * lp * lq;
    // g is a difference of two log primitives, each of size about S (1 + |ln S|) with S the
    // extent of the pair (coordinates are scaled to the pair, so S and |ln r| stay moderate): its
    // rounding error is about 1e-15 S whatever lp is (the terms do not shrink with a short P). The
    // noise accepted over all of Q is then 1e-14 S lq: the floor that doubles allow.
    const double extent = lp + lq + glm::length(q0 - p0);
    const double noise = 1e-14 * extent;
    // Near misses. Where q(t) passes at a small distance from P, g has a feature of width ρ in t
    // that is not a singularity on the real line:
    //  - near the closest approach t*, at distance h0 and an angle θ between the edges,
    //    g = smooth + π D(t) with D = √(h0² + sin²θ (t − t*)²) = sinθ √((t − t*)² + ρ²),
    //    ρ = h0 / sinθ: complex singularities at t* ± iρ;
    //  - near an end p of P, g's terms are functions of |q(t) − p|² = (t − t_p)² + ρ², ρ the
    //    distance from p to Q's line: singular at t_p ± iρ.
    // A panel that reaches the feature but is much wider than ρ has no node within ρ of it (the
    // outermost K15 node is 0.0043 of the panel from its end), so K15 and G7 both miss the
    // feature's integral, π sinθ ρ² (ln(2W/ρ) + ½) / 2 ≤ 2 ρ² (ln(2W/ρ) + 1) over a panel of
    // width W, and agree: |K − G| says converged when it is not. (A sliver 1.4e-5 wide whose long
    // edge passes 2e-6 from another polygon's edge: one panel of 0.41 accepted at
    // |K − G| = 4e-14 with an error of 1.5e-11; reciprocity off by 1.6e-6 relative.)
    // So where that part could exceed 1/16 of the tolerance, cuts are added at c ± ρ 4^k
    // (k = 0, 1, … while ρ 4^k < lq / 8). Every panel then either lies within ρ of the feature's
    // centre, or is 3 ρ 4^k wide at ρ 4^k from it, or is the outermost one, at ≥ lq / 32 from
    // it and ≤ lq wide: the singularities are at least 1/16 of each panel's half-width outside
    // it, the rules' nodes see the feature, |K − G| is a true estimate, and the adaptive
    // bisection does the rest. ρ is taken at the cut c itself, |q(c) − p| (and |q(c) − P| / sinθ
    // for the closest approach): the distance from c to the singularity, also when c is clamped
    // to an end of Q. Below the threshold (ρ ≲ 1e-8 of the edges) the feature is below the
    // tolerance; ρ ≤ min_width (a shared vertex, a touching edge, up to rounding) is a
    // singularity at the cut, which bisection resolves geometrically. From ρ > 4ε lq to lq / 8
    // is at most 24 factors of 4 (kMaxGradedCutsPerSide = 28).
    const double min_width = 4.0 * std::numeric_limits<double>::epsilon() * lq;
    std::array<double, 5 + 6 * kMaxGradedCutsPerSide> cuts{};
    std::size_t n_cuts = 0;
    for (double c : {0.0, t_near, t_p0, t_p1, lq}) cuts[n_cuts++] = c;
    const auto grade = [&](double c, double rho) {
        if (!(rho > min_width) || !(rho < 0.125 * lq)) return;
        if (2.0 * rho * rho * (std::log(2.0 * lq / rho) + 1.0) <= tol / 16.0) return;
        double r = rho;
        for (int k = 0; k < kMaxGradedCutsPerSide && r < 0.125 * lq; ++k, r *= 4.0) {
            if (c - r > 0.0) cuts[n_cuts++] = c - r;
            if (c + r < lq) cuts[n_cuts++] = c + r;
        }
    };
    const auto q_at = [&](double t) { return q0 + t * e; };
    const auto distance_to_p = [&](const Vec3& x) {
        const double s = std::clamp(glm::dot(x - p0, d), 0.0, lp);
        return glm::length(x - (p0 + s * d));
    };
    grade(t_near, distance_to_p(q_at(t_near)) / sin_angle);
    grade(t_p0, glm::length(q_at(t_p0) - p0));
    grade(t_p1, glm::length(q_at(t_p1) - p1));
    std::sort(cuts.begin(), cuts.begin() + static_cast<std::ptrdiff_t>(n_cuts));
    // Budget: see kContourEvalsPerEdgePair (analytic.hpp). Splitting stops once kEdgePairSplitBudget
    // evaluations are spent; the panels then pending (≤ kMaxQuadDepth on the stack, and the cuts'
    // panels not yet begun: ≤ 3 + 6 kMaxGradedCutsPerSide) cost 15 each, so the pair never exceeds
    // kContourEvalsPerEdgePair.
    const std::uint64_t limit = work.evaluations + kEdgePairSplitBudget;
    double integral = 0.0;
    for (std::size_t i = 0; i + 1 < n_cuts; ++i)
        if (cuts[i + 1] > cuts[i])
            integral += integrate(g, cuts[i], cuts[i + 1], tol, noise, min_width, kMaxQuadDepth, limit, work);
    return cos_angle * integral;
}


// Crossing-number test of a point already in the polygon's plane, in the 2D projection that
// drops the normal's largest component.
bool point_in_polygon(const Vec3& x, std::span<const Vec3> poly, const Vec3& n) {
    int ax = 0;
    if (std::abs(n.y) > std::abs(n[ax])) ax = 1;
    if (std::abs(n.z) > std::abs(n[ax])) ax = 2;
    const int i0 = (ax + 1) % 3, i1 = (ax + 2) % 3;
    bool inside = false;
    const std::size_t k = poly.size();
    for (std::size_t i = 0, j = k - 1; i < k; j = i++) {
        const Vec3& a = poly[i];
        const Vec3& b = poly[j];
        if ((a[i1] > x[i1]) != (b[i1] > x[i1]) &&
            x[i0] < (b[i0] - a[i0]) * (x[i1] - a[i1]) / (b[i1] - a[i1]) + a[i0])
            inside = !inside;
    }
    return inside;
}


// ---- far field ---------------------------------------------------------------------------


// Far-field rule: 20 points. With the nearest singularity at least 1.59 half-lengths away
// (see far_field_integral), Gauss converges like ρ^(−2n), ρ = 1.59 + √(1 + 1.59²) = 3.47:
// 3.47^(−40) ≈ 1e-21, below rounding.
const GaussRule& gauss20() {
    static const GaussRule rule = gauss_legendre(20);
    return rule;
}

double bounding_radius(std::span<const Vec3> poly, const Vec3& c) {
    double r = 0.0;
    for (const Vec3& v : poly) r = std::max(r, glm::length(v - c));
    return r;
}

// ∫_P F(x → Q) dA for a polygon P (unit normal n, CCW) and a polygon Q wholly in front of P's
// plane, with Lambert's formula as the integrand. Green's theorem in P's plane,
//   ∫_P f dA = ∮_∂P (∫_{x0}^{x} f(s, y) ds) dy,
// needs no triangulation (non-convex P is fine); x0 is P's leftmost x, so every point used
// lies in P's bounding square, within √2·R of its centroid (R: P's bounding radius). The
// caller guarantees Q is at least 2R beyond P's bounding sphere: every singularity of f is then
// ≥ 2R + R − √2 R ≥ 1.59 R from the points used, and the spans integrated are ≤ 2R long.
// Used where the contour integral would cancel: Lambert's terms are O(L/D) and their sum
// O((L/D)²), so it loses only log10(D/L) digits instead of the contour form's 2·log10(D/L).
double far_field_integral(std::span<const Vec3> poly, const Vec3& n, std::span<const Vec3> q,
                          std::uint64_t& evaluations) {
    Vec3 t1, t2;
    orthonormal_basis(n, t1, t2);
    const Vec3 c = polygon_centroid(poly);
    const GaussRule& g = gauss20();
    const std::size_t k = poly.size();
    double x0 = 0.0;
    for (const Vec3& v : poly) x0 = std::min(x0, glm::dot(v - c, t1));
    double total = 0.0;
    for (std::size_t e = 0; e < k; ++e) {
        const Vec3 a = poly[e] - c, b = poly[(e + 1) % k] - c;
        const double xa = glm::dot(a, t1), ya = glm::dot(a, t2);
        const double xb = glm::dot(b, t1), yb = glm::dot(b, t2);
        if (yb == ya) continue;
        evaluations += g.x.size() * g.x.size();
        double edge = 0.0;
        for (std::size_t i = 0; i < g.x.size(); ++i) {
            const double tau = 0.5 * (1.0 + g.x[i]);
            const double x = xa + tau * (xb - xa), y = ya + tau * (yb - ya);
            const double half = 0.5 * (x - x0), mid = 0.5 * (x + x0);
            double inner = 0.0;
            for (std::size_t j = 0; j < g.x.size(); ++j)
                inner += g.w[j] * lambert_sum(c + (mid + half * g.x[j]) * t1 + y * t2, n, q);
            edge += g.w[i] * half * inner;
        }
        total += 0.5 * (yb - ya) * edge;
    }
    return total / (2.0 * kPi);
}

// ---- closed forms ------------------------------------------------------------------------

}  // namespace

// ---- polygons ----------------------------------------------------------------------------

double ff_point_polygon(const Vec3& p, const Vec3& n, std::span<const Vec3> given) {
    const char* fn = "ff_point_polygon";
    std::vector<Vec3> flat;
    const std::span<const Vec3> poly = planar_polygon(fn, "the polygon", given, flat);
    const double len = glm::length(n);
    if (!(len > 0.0) || !std::isfinite(len))
        throw InputError(fmt::format("{}: the normal must be non-zero and finite", fn));
    const Vec3 un = n / len;
    // A point in the polygon's plane sees it edge-on: F = 0. Within 1e-12 of the size of that
    // plane, or within the rounding of the coordinates (geometric_tolerance), the directions to
    // the vertices are rounding noise, so the same answer is given.
    const double size = polygon_max_edge(poly);
    const double coord = std::max({max_abs_coordinate(poly), std::abs(p.x), std::abs(p.y), std::abs(p.z)});
    if (std::abs(glm::dot(p - polygon_centroid(poly), polygon_normal(poly))) <=
        geometric_tolerance(1e-12, size, coord))
        return 0.0;
    std::vector<Vec3> front;
    clip_to_front(poly, p, un, front);
    if (front.size() < 3) return 0.0;
    return std::abs(lambert_sum(p, un, front)) / (2.0 * kPi);
}

double ff_point_polygon_unclipped(const Vec3& p, const Vec3& unit_n, std::span<const Vec3> poly) {
    return std::abs(lambert_sum(p, unit_n, poly)) / (2.0 * kPi);
}

std::uint64_t ff_polygon_polygon_budget(std::size_t k1, std::size_t k2) {
    const std::uint64_t a = k1, b = k2;
    return std::max(a * b * kContourEvalsPerEdgePair, std::max(a, b) * kFarFieldEvalsPerEdge);
}

namespace {

void record(const AnalyticCallInfo& info) {
    AnalyticStats call;
    call.calls = 1;
    call.evaluations = info.evaluations;
    call.max_evaluations_per_call = info.evaluations;
    call.fallbacks = info.fallbacks;
    call.fallback_calls = info.fallbacks > 0 ? 1 : 0;
    add_stats(call);
}

double polygon_polygon(std::span<const Vec3> given1, std::span<const Vec3> given2, AnalyticCallInfo& info) {
    const char* fn = "ff_polygon_polygon";
    std::vector<Vec3> flat1, flat2;
    const std::span<const Vec3> p1 = planar_polygon(fn, "polygon 1", given1, flat1);
    const std::span<const Vec3> p2 = planar_polygon(fn, "polygon 2", given2, flat2);
    // Work relative to polygon 1's centroid and in units of the pair's size: offsets of 1e5
    // keep their digits, and ln r stays O(1). F is invariant under both.
    const Vec3 origin = polygon_centroid(p1);
    const double scale = std::max(polygon_max_edge(p1), polygon_max_edge(p2));
    const double coord = std::max(max_abs_coordinate(p1), max_abs_coordinate(p2));
    std::vector<Vec3> a(p1.size()), b(p2.size());
    for (std::size_t i = 0; i < p1.size(); ++i) a[i] = (p1[i] - origin) / scale;
    for (std::size_t i = 0; i < p2.size(); ++i) b[i] = (p2[i] - origin) / scale;
    const Vec3 n1 = polygon_normal(a), n2 = polygon_normal(b);
    const Vec3 c1 = polygon_centroid(a), c2 = polygon_centroid(b);
    const double area1 = polygon_area(a);

    // cosθ1 > 0 only in front of plane 1 and cosθ2 > 0 only in front of plane 2, and the two
    // conditions are independent, so clipping each polygon by the other's plane keeps exactly
    // the pairs of points that exchange energy front to front.
    // Vertices within rounding of the other's plane count as on it (see clip_to_front).
    const double in_plane = geometric_tolerance(1e-12, 1.0, coord / scale);
    std::vector<Vec3> a_front, b_front;
    clip_to_front(a, c2, n2, a_front, in_plane);
    clip_to_front(b, c1, n1, b_front, in_plane);
    if (a_front.size() < 3 || b_front.size() < 3) return 0.0;
    info.clipped_vertices1 = a_front.size();
    info.clipped_vertices2 = b_front.size();
    info.budget = ff_polygon_polygon_budget(a_front.size(), b_front.size());
    // A polygon lying in the other's plane (to 1e-12 of the size, the planarity rounding, or to
    // the rounding of the input coordinates, in units of the pair's size) sees it at cosθ = 0.
    double height1 = 0.0, height2 = 0.0;
    for (const Vec3& v : a_front) height1 = std::max(height1, glm::dot(v - c2, n2));
    for (const Vec3& v : b_front) height2 = std::max(height2, glm::dot(v - c1, n1));
    if (height1 <= in_plane || height2 <= in_plane) return 0.0;

    // Far apart (the bounding spheres at least 2 radii of the smaller one apart): integrate
    // Lambert's formula over the smaller polygon (reciprocity: A1 F12 = A2 F21) instead of the
    // contour integral, whose O(L² ln D) terms cancel to O(L⁴/D²).
    const Vec3 ca = polygon_centroid(a_front), cb = polygon_centroid(b_front);
    const double ra = bounding_radius(a_front, ca), rb = bounding_radius(b_front, cb);
    if (glm::length(ca - cb) - ra - rb >= 2.0 * std::min(ra, rb)) {
        info.method = AnalyticCallInfo::Method::far_field;
        const double a1f12 = ra <= rb ? far_field_integral(a_front, n1, b_front, info.evaluations)
                                      : far_field_integral(b_front, n2, a_front, info.evaluations);
        return std::max(0.0, a1f12 / area1);
    }

    info.method = AnalyticCallInfo::Method::contour;
    QuadWork work;
    double sum = 0.0;
    const std::size_t ka = a_front.size(), kb = b_front.size();
    for (std::size_t i = 0; i < ka; ++i)
        for (std::size_t j = 0; j < kb; ++j)
            sum += edge_pair(a_front[i], a_front[(i + 1) % ka], b_front[j], b_front[(j + 1) % kb], work);
    info.evaluations = work.evaluations;
    info.fallbacks = work.fallbacks;
    // |cos| ≤ 1 per edge pair, so the panels' error bounds add up to one on the double integral.
    info.error_bound = work.fallback_error / (2.0 * kPi * area1);
    // Both contours counter-clockwise seen from their fronts, facing each other: the double
    // contour integral is then +2π A1 F12. Rounding can leave −1e-17 for F = 0 exactly.
    return std::max(0.0, sum / (2.0 * kPi * area1));
}

}  // namespace

double ff_polygon_polygon(std::span<const Vec3> p1, std::span<const Vec3> p2, AnalyticCallInfo& info) {
    info = AnalyticCallInfo{};
    const double f = polygon_polygon(p1, p2, info);
    FFCUBE_CHECK_MSG(info.evaluations <= info.budget, "ff_polygon_polygon exceeded its evaluation budget");
    record(info);
    return f;
}

double ff_polygon_polygon(std::span<const Vec3> p1, std::span<const Vec3> p2) {
    AnalyticCallInfo info;
    return ff_polygon_polygon(p1, p2, info);
}

AnalyticStats analytic_stats() {
    const std::lock_guard lock(g_stats_mutex);
    return g_stats;
}

void reset_analytic_stats() {
    const std::lock_guard lock(g_stats_mutex);
    g_stats = AnalyticStats{};
}

void merge_analytic_stats(const AnalyticStats& other) { add_stats(other); }


double ff_polygon_polygon_mc(std::span<const Vec3> given1, std::span<const Vec3> given2,
                             std::uint64_t samples, std::uint64_t seed) {
    const char* fn = "ff_polygon_polygon_mc";
    std::vector<Vec3> flat1, flat2;
    const std::span<const Vec3> p1 = planar_polygon(fn, "polygon 1", given1, flat1);
    const std::span<const Vec3> p2 = planar_polygon(fn, "polygon 2", given2, flat2);
    if (samples == 0) throw InputError(fmt::format("{}: samples must be at least 1", fn));
    const Vec3 n1 = polygon_normal(p1), n2 = polygon_normal(p2);
    Vec3 t1, t2;
    orthonormal_basis(n1, t1, t2);
    // Fan triangles of polygon 1 with their cumulative areas, for area-uniform sampling.
    const std::size_t tris = p1.size() - 2;
    std::vector<double> cdf(tris);
    double total = 0.0;
    for (std::size_t i = 0; i < tris; ++i) {
        total += 0.5 * glm::length(glm::cross(p1[i + 1] - p1[0], p1[i + 2] - p1[0]));
        cdf[i] = total;
    }
    std::mt19937_64 rng(seed);
    const auto uniform = [&rng] { return static_cast<double>(rng() >> 11) * 0x1.0p-53; };
    std::uint64_t hits = 0;
    for (std::uint64_t s = 0; s < samples; ++s) {
        const double pick = uniform() * total;
        const std::size_t tri = std::min<std::size_t>(
            static_cast<std::size_t>(std::upper_bound(cdf.begin(), cdf.end(), pick) - cdf.begin()),
            tris - 1);
        double u = uniform(), v = uniform();
        if (u + v > 1.0) {
            u = 1.0 - u;
            v = 1.0 - v;
        }
        const Vec3 x = p1[0] + u * (p1[tri + 1] - p1[0]) + v * (p1[tri + 2] - p1[0]);
        // Cosine-distributed direction (Malley): uniform on the disk, lifted to the hemisphere.
        const double phi = 2.0 * kPi * uniform(), r2 = uniform();
        const double sin_t = std::sqrt(r2), cos_t = std::sqrt(1.0 - r2);
        const Vec3 dir = sin_t * std::cos(phi) * t1 + sin_t * std::sin(phi) * t2 + cos_t * n1;
        const double dn = glm::dot(dir, n2);
        if (!(dn < 0.0)) continue;  // parallel to polygon 2 or reaching its back
        const double t = glm::dot(p2[0] - x, n2) / dn;
        if (!(t > 0.0)) continue;
        if (point_in_polygon(x + t * dir, p2, n2)) ++hits;
    }
    return static_cast<double>(hits) / static_cast<double>(samples);
}

}  // namespace ffcube
