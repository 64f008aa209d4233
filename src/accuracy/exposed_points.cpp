#include "accuracy/exposed_points.hpp"

#include <glm/geometric.hpp>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <numeric>

#include "accuracy/patch_set.hpp"
#include "accuracy/sender_visibility.hpp"
#include "accuracy/spatial_grid.hpp"
#include "ffcube/geometry/polygon.hpp"

namespace ffcube {

using P2 = std::array<double, 2>;

Moments polygon_moments(std::span<const P2> poly) {
    Moments m{};
    const std::size_t n = poly.size();
    for (std::size_t k = 0; k < n; ++k) {
        const auto [x0, y0] = poly[k];
        const auto [x1, y1] = poly[(k + 1) % n];
        const double c = x0 * y1 - x1 * y0;
        m[0] += c / 2;
        m[1] += (x0 + x1) * c / 6;
        m[2] += (y0 + y1) * c / 6;
        m[3] += (x0 * x0 + x0 * x1 + x1 * x1) * c / 12;
        m[4] += (x0 * y1 + 2 * x0 * y0 + 2 * x1 * y1 + x1 * y0) * c / 24;
        m[5] += (y0 * y0 + y0 * y1 + y1 * y1) * c / 12;
    }
    return m;
}

Moments monomials(double x, double y) { return {1, x, y, x * x, x * y, y * y}; }

namespace {

// Solves the 6 × 6 system a x = b in place (Gaussian elimination, partial pivoting); false when
// a pivot is below 1e-12 of the largest entry (the points do not determine a quadratic).
bool solve6(std::array<std::array<double, 6>, 6>& a, Moments& b) {
    double scale = 0;
    for (const auto& row : a)
        for (double v : row) scale = std::max(scale, std::abs(v));
    for (std::size_t c = 0; c < 6; ++c) {
        std::size_t p = c;
        for (std::size_t r = c + 1; r < 6; ++r)
            if (std::abs(a[r][c]) > std::abs(a[p][c])) p = r;
        if (!(std::abs(a[p][c]) > 1e-12 * scale)) return false;
        std::swap(a[p], a[c]);
        std::swap(b[p], b[c]);
        for (std::size_t r = c + 1; r < 6; ++r) {
            const double f = a[r][c] / a[c][c];
            for (std::size_t k = c; k < 6; ++k) a[r][k] -= f * a[c][k];
            b[r] -= f * b[c];
        }
    }
    for (std::size_t c = 6; c-- > 0;) {
        for (std::size_t k = c + 1; k < 6; ++k) b[c] -= a[c][k] * b[k];
        b[c] /= a[c][c];
    }
    return true;
}

// The convex polygon clipped to the rectangle [lo, hi] (Sutherland–Hodgman, one side at a time).
std::vector<P2> clip_to_rect(std::vector<P2> poly, const P2& lo, const P2& hi) {
    for (int side = 0; side < 4; ++side) {
        const std::size_t axis = side % 2;
        const bool upper = side >= 2;
        const double bound = upper ? hi[axis] : lo[axis];
        auto inside = [&](const P2& p) { return upper ? p[axis] <= bound : p[axis] >= bound; };
        std::vector<P2> out;
        for (std::size_t k = 0; k < poly.size(); ++k) {
            const P2& a = poly[k];
            const P2& b = poly[(k + 1) % poly.size()];
            if (inside(a)) out.push_back(a);
            if (inside(a) != inside(b)) {
                const double t = (bound - a[axis]) / (b[axis] - a[axis]);
                out.push_back({a[0] + t * (b[0] - a[0]), a[1] + t * (b[1] - a[1])});
            }
        }
        poly = std::move(out);
        if (poly.empty()) break;
    }
    return poly;
}

// Patch i in its own plane: origin at its centroid, axes (t, b) with t × b = its normal (so its
// vertices stay counter-clockwise), lengths in units of its size.
struct Frame {
    Vec3 origin, t, b;
    double size;
    Frame(const Patch& p) : origin(p.centroid), size(p.size) { orthonormal_basis(p.normal, t, b); }
    P2 local(const Vec3& x) const { return {glm::dot(x - origin, t) / size, glm::dot(x - origin, b) / size}; }
    Vec3 world(const P2& u) const { return origin + size * (u[0] * t + u[1] * b); }
};

std::vector<P2> local_polygon(const Frame& f, const accuracy::Poly& poly) {
    std::vector<P2> out;
    for (const Vec3& v : poly.span()) out.push_back(f.local(v));
    return out;
}

}  // namespace

bool fit_weights(std::span<const P2> points, const Moments& target, std::vector<double>& w) {
    if (points.size() < 6) return false;
    std::vector<Moments> a(points.size());
    for (std::size_t q = 0; q < points.size(); ++q) a[q] = monomials(points[q][0], points[q][1]);
    std::array<std::array<double, 6>, 6> aat{};
    Moments rhs = target;
    for (std::size_t q = 0; q < points.size(); ++q)
        for (std::size_t r = 0; r < 6; ++r) {
            rhs[r] -= a[q][r] * w[q];
            for (std::size_t c = 0; c < 6; ++c) aat[r][c] += a[q][r] * a[q][c];
        }
    if (!solve6(aat, rhs)) return false;
    for (std::size_t q = 0; q < points.size(); ++q)
        for (std::size_t r = 0; r < 6; ++r) w[q] += a[q][r] * rhs[r];
    return true;
}

ExposedPoints::ExposedPoints(const Scene& scene)
    : scene_(scene),
      patches_(std::make_unique<accuracy::PatchSet>(scene)),
      grid_(std::make_unique<accuracy::SpatialGrid>(*patches_)),
      rays_(scene) {}

ExposedPoints::~ExposedPoints() = default;

bool ExposedPoints::cut(std::uint32_t i) const {
    const Patch& pi = scene_.patches[i];
    const Frame f(pi);
    const std::vector<P2> outline = local_polygon(f, patches_->polys[i]);
    std::vector<std::uint32_t> near;
    // The box grown by the largest gap of a cover (accuracy::covers_part), which need not touch i.
    const accuracy::Box& box = patches_->boxes[i];
    const Vec3 grow(accuracy::kCoverGap * pi.size);
    grid_->query(accuracy::Box{box.lo - grow, box.hi + grow}, near);
    for (std::uint32_t q : near) {
        if (q == i) continue;
        // A plate just in front of i over part of it (a light below a ceiling) encloses that part.
        if (accuracy::covers_part(*patches_, i, q)) return true;
        const accuracy::Poly& poly = patches_->polys[q];
        const double tol = accuracy::plane_tolerance(pi, scene_.patches[q]);
        std::array<double, 4> d{};
        bool front = false;
        for (std::size_t k = 0; k < poly.n; ++k) {
            d[k] = glm::dot(poly.v[k] - pi.centroid, pi.normal);
            if (std::abs(d[k]) <= tol) d[k] = 0;
            front = front || d[k] > 0;
        }
        if (!front) continue;
        // Where q meets i's plane: a segment (q is convex), from its vertices in the plane and
        // its edges that cross it.
        std::vector<Vec3> meet;
        for (std::size_t k = 0; k < poly.n; ++k) {
            const std::size_t l = (k + 1) % poly.n;
            if (d[k] == 0) meet.push_back(poly.v[k]);
            if (d[k] * d[l] < 0) meet.push_back(poly.v[k] + (poly.v[l] - poly.v[k]) * (d[k] / (d[k] - d[l])));
        }
        if (meet.size() < 2) continue;
        // The points lie on one line: its ends are the point farthest from any of them, and the
        // point farthest from that one.
        const auto farthest = [&](const Vec3& from) {
            return *std::max_element(meet.begin(), meet.end(), [&](const Vec3& a, const Vec3& b) {
                return glm::length(a - from) < glm::length(b - from);
            });
        };
        const Vec3 a = farthest(meet[0]), b = farthest(a);
        // Margin: 1e-6 of i's size, far above the rounding of the plane test, far below a cell.
        if (accuracy::segment_inside(outline, f.local(a), f.local(b), 1e-6)) return true;
    }
    return false;
}

bool ExposedPoints::enclosed(std::uint32_t i, const Vec3& at) const {
    const Patch& p = scene_.patches[i];
    Vec3 t, b;
    orthonormal_basis(p.normal, t, b);
    // Above the plane by 1e-5 of the patch size (the hemicube's eye offset), and by more than
    // the float rounding of the ray scene's unit-scaled coordinates.
    const Vec3 origin = at + std::max(1e-5 * p.size, 1e-6 * scene_.extent()) * p.normal;
    const double tilt = kTiltDegrees * std::numbers::pi / 180;
    const double c = std::cos(tilt), s = std::sin(tilt);
    const std::array<Vec3, 5> dirs{p.normal, c * p.normal + s * t, c * p.normal - s * t, c * p.normal + s * b,
                                   c * p.normal - s * b};
    for (const Vec3& d : dirs)
        if (!rays_.first_hit(origin, d, i).back) return false;
    return true;
}

// Splits the exposed cells into 4 × 4 strata of about equal area (by x, then by y within each
// column), and picks in each stratum the cell nearest its centroid; w0 the strata's areas.
void ExposedPoints::choose_points(std::vector<Cell>& cells, std::vector<std::size_t>& chosen,
                                  std::vector<double>& w0) const {
    const int k = 4;
    std::vector<std::size_t> order(cells.size());
    std::iota(order.begin(), order.end(), std::size_t{0});
    auto split = [&](std::size_t lo, std::size_t hi, std::size_t axis, auto&& each) {
        std::stable_sort(order.begin() + static_cast<long>(lo), order.begin() + static_cast<long>(hi),
                         [&](std::size_t a, std::size_t b) { return cells[a].c[axis] < cells[b].c[axis]; });
        double total = 0;
        for (std::size_t r = lo; r < hi; ++r) total += cells[order[r]].area;
        std::size_t start = lo;
        double run = 0;
        for (int part = 1; part <= k; ++part) {
            std::size_t end = start;
            while (end < hi && (part == k || run + 0.5 * cells[order[end]].area <= total * part / k))
                run += cells[order[end++]].area;
            if (end > start) each(start, end);
            start = end;
        }
    };
    split(0, cells.size(), 0, [&](std::size_t a, std::size_t b) {
        split(a, b, 1, [&](std::size_t lo, std::size_t hi) {
            double area = 0, cx = 0, cy = 0;
            for (std::size_t r = lo; r < hi; ++r) {
                const Cell& c = cells[order[r]];
                area += c.area, cx += c.area * c.c[0], cy += c.area * c.c[1];
            }
            cx /= area, cy /= area;
            std::size_t best = order[lo];
            double best_d = INFINITY;
            for (std::size_t r = lo; r < hi; ++r) {
                const Cell& c = cells[order[r]];
                const double dd = std::hypot(c.c[0] - cx, c.c[1] - cy);
                if (dd < best_d) best_d = dd, best = order[r];
            }
            chosen.push_back(best);
            w0.push_back(area);
        });
    });
}

bool ExposedPoints::rule(std::uint32_t i, std::vector<Vec3>& points, std::vector<double>& weights) const {
    if (!cut(i)) return false;
    const Frame f(scene_.patches[i]);
    const std::vector<P2> outline = local_polygon(f, patches_->polys[i]);
    const double area = polygon_moments(outline)[0];
    P2 lo{INFINITY, INFINITY}, hi{-INFINITY, -INFINITY};
    for (const P2& v : outline)
        for (std::size_t a = 0; a < 2; ++a) lo[a] = std::min(lo[a], v[a]), hi[a] = std::max(hi[a], v[a]);
    std::vector<Cell> cells;
    Moments target{};
    bool any_enclosed = false;
    for (int cy = 0; cy < kCells; ++cy)
        for (int cx = 0; cx < kCells; ++cx) {
            const P2 a{lo[0] + (hi[0] - lo[0]) * cx / kCells, lo[1] + (hi[1] - lo[1]) * cy / kCells};
            const P2 b{lo[0] + (hi[0] - lo[0]) * (cx + 1) / kCells, lo[1] + (hi[1] - lo[1]) * (cy + 1) / kCells};
            const std::vector<P2> piece = clip_to_rect(outline, a, b);
            if (piece.size() < 3) continue;
            const Moments m = polygon_moments(piece);
            if (!(m[0] > 1e-12 * area)) continue;
            const P2 c{m[1] / m[0], m[2] / m[0]};
            if (enclosed(i, f.world(c))) {
                any_enclosed = true;
                continue;
            }
            cells.push_back({c, m[0], m});
            for (std::size_t r = 0; r < 6; ++r) target[r] += m[r];
        }
    if (!any_enclosed) return false;
    for (double& t : target) t /= area;
    std::vector<std::size_t> chosen;
    std::vector<double> w;
    choose_points(cells, chosen, w);
    for (double& x : w) x /= area;
    std::vector<P2> at;
    for (std::size_t c : chosen) at.push_back(cells[c].c);
    // When the points cannot fit a quadratic, the strata's areas. A fit with a negative weight
    // is not used either: the row is the weighted sum of the points' hemicube rows, and only
    // weights ≥ 0 (of sum ≤ 1: the exposed share of i) keep every entry in [0, 1] and the row
    // sum at most 1 (docs/robustness.md, "No row out of range"; a patch cut by faces that pass
    // through it gave entries of −0.058 and row sums of 1.46).
    std::vector<double> strata = w;
    if (fit_weights(at, target, w) && std::any_of(w.begin(), w.end(), [](double x) { return !(x >= 0); })) w = strata;
    points.clear();
    for (const P2& u : at) points.push_back(f.world(u));
    weights = std::move(w);
    return true;
}

}  // namespace ffcube
