// Near-field correction: near-pair search and the conservative shaft (occlusion) test.
#include "ffcube/accuracy/near_field.hpp"

#include <fmt/format.h>
#include <glm/geometric.hpp>

#include <algorithm>
#include <array>
#include <bit>
#include <cmath>
#include <limits>
#include <numbers>
#include <unordered_map>
#include <vector>

#include "ffcube/core/error.hpp"
#include "ffcube/core/timer.hpp"
#include "ffcube/geometry/analytic.hpp"
#include "ffcube/geometry/polygon.hpp"
#include "ffcube/geometry/quadrature.hpp"

namespace ffcube {

namespace {

struct Box {
    Vec3 lo{0.0}, hi{0.0};
    bool overlaps(const Box& o) const {
        return lo.x <= o.hi.x && o.lo.x <= hi.x && lo.y <= o.hi.y && o.lo.y <= hi.y && lo.z <= o.hi.z && o.lo.z <= hi.z;
    }
};

// Patch vertices without a triangle's repeated last one.
struct Poly {
    std::array<Vec3, 4> v{};
    std::size_t n = 3;
    std::span<const Vec3> span() const { return {v.data(), n}; }
};

// How far from a patch's plane a vertex of another counts as lying in it: 1e-9 of the pair's
// size (the planarity tolerance of geometry/analytic.hpp), plus the rounding of coordinates far
// from the origin (16 ulps of the largest one: a scene offset by 1e5 has its patch normals off by
// 1e-10 and its vertices off their planes by 1e-11).
double plane_tolerance(const Patch& a, const Patch& b) {
    const double coord = std::max({std::abs(a.centroid.x), std::abs(a.centroid.y), std::abs(a.centroid.z),
                                   std::abs(b.centroid.x), std::abs(b.centroid.y), std::abs(b.centroid.z)});
    return 1e-9 * std::max(a.size, b.size) + 16 * std::numeric_limits<double>::epsilon() * coord;
}

// ff_polygon_polygon for two facing patches, with the vertices of each that lie within
// plane_tolerance of the other's plane moved to that distance in front of it. Why: rounding
// leaves such vertices a hair *behind* the plane (a box's ceiling meshed at z =
// 0.99999999999999978 puts a wall's top vertices 1e-16 behind it; an offset of 1e5 does the same
// at 1e-11); the contour integral then clips a sliver of that height, and its adaptive
// quadrature, whose tolerance scales with the sliver, recurses to its depth limit (2^50
// evaluations: it never returns). The move changes F by O(1e-9) relative.
double exact_ff(const Poly& a, const Patch& pa, const Poly& b, const Patch& pb) {
    const double tol = plane_tolerance(pa, pb);
    auto lift = [&](const Poly& p, const Patch& other) {
        Poly q = p;
        for (std::size_t k = 0; k < q.n; ++k) {
            const double d = glm::dot(q.v[k] - other.centroid, other.normal);
            if (std::abs(d) <= tol) q.v[k] += (tol - d) * other.normal;
        }
        return q;
    };
    const Poly a2 = lift(a, pb), b2 = lift(b, pa);
    return ff_polygon_polygon(a2.span(), b2.span());
}

// Sutherland–Hodgman: the part of `in` where dot(v − o, m) ≥ 0.
void clip_front(std::span<const Vec3> in, const Vec3& o, const Vec3& m, std::vector<Vec3>& out) {
    out.clear();
    const std::size_t k = in.size();
    for (std::size_t e = 0; e < k; ++e) {
        const Vec3 &a = in[e], &b = in[(e + 1) % k];
        const double da = glm::dot(a - o, m), db = glm::dot(b - o, m);
        if (da >= 0) out.push_back(a);
        if ((da > 0 && db < 0) || (da < 0 && db > 0)) out.push_back(a + (b - a) * (da / (da - db)));
    }
}

// Points of the sender rule for separated near pairs (separated_ff): 6 × 6 Gauss.
constexpr int kSeparatedRule = 6;

// F_ij for a facing pair whose bounding spheres are at least 2 radii of the smaller one apart
// (the regime in which ff_polygon_polygon itself switches from the contour integral to
// integrating Lambert's formula, with 4 × 20 × 20 points). Here: each patch clipped to the front
// of the other's plane, Lambert's formula from the points of a 6 × 6 Gauss rule on the smaller
// clipped patch (fan triangles when clipping made it a pentagon) to the other; reciprocity gives
// F_ij from whichever side was integrated. Against ff_polygon_polygon over 3,000 random pairs
// (parallelograms and triangles, sizes 1e-2..1e2 apart, gaps of 2–3 small radii): worst relative
// error 3.6e-10, at about an eighth of the cost (1e-7 at 5 × 5, 6e-6 at 4 × 4).
double separated_ff(const Poly& a, const Patch& pa, double ra, const Poly& b, const Patch& pb, double rb) {
    std::vector<Vec3> af, bf;
    clip_front(a.span(), pb.centroid, pb.normal, af);
    clip_front(b.span(), pa.centroid, pa.normal, bf);
    if (af.size() < 3 || bf.size() < 3) return 0.0;
    const bool a_small = ra <= rb;
    const std::vector<Vec3>& s = a_small ? af : bf;
    const std::vector<Vec3>& o = a_small ? bf : af;
    const Vec3& ns = a_small ? pa.normal : pb.normal;
    std::vector<Vec3> pts;
    std::vector<double> wts;
    double integral = 0;  // ∫_S F(x → O) dA = A_i F_ij = A_j F_ji
    const auto add = [&](std::span<const Vec3> piece) {
        patch_quadrature(piece, kSeparatedRule, pts, wts);
        const double area = polygon_area(piece);
        for (std::size_t k = 0; k < pts.size(); ++k) {
            bool whole = true;
            for (const Vec3& v : o) whole = whole && glm::dot(v - pts[k], ns) > 0;
            integral += wts[k] * area *
                        (whole ? ff_point_polygon_unclipped(pts[k], ns, o) : ff_point_polygon(pts[k], ns, o));
        }
    };
    if (s.size() <= 4) {
        add(s);
    } else {
        for (std::size_t t = 1; t + 1 < s.size(); ++t) add(std::array<Vec3, 3>{s[0], s[t], s[t + 1]});
    }
    return std::max(0.0, integral / pa.area);
}


}  // namespace

// An inner row whose sum is within this of 1 counts as closed. Float storage of a hemicube
// row's entries (2^-24 relative each) moves a closed row's sum by up to 6e-8, so the line must
// be above that; a row open by less than 1e-7 (a few pixels at grazing angles) is changed by
// at most that much when rebalanced to 1.
constexpr double kClosedRowTolerance = 1e-7;

struct NearFieldCorrector::Impl {
    const Scene& scene;
    NearFieldOptions options;
    std::vector<Poly> polys;
    std::vector<Box> boxes;
    std::vector<double> radius;  // bounding sphere about the centroid
    double max_size = 0;
    // Uniform grid of bounding boxes: cell (x, y, z) of side h from `origin`, hashed.
    Vec3 origin{0.0};
    double h = 1;
    std::unordered_map<std::uint64_t, std::vector<std::uint32_t>> cells;
    std::vector<std::uint32_t> big;  // patches too large for the grid, checked by every query

    static constexpr long kMaxCellsPerQuery = 4096;  // beyond: scan every patch instead

    std::array<long, 3> cell_of(const Vec3& p) const {
        const Vec3 c = (p - origin) / h;
        return {static_cast<long>(std::floor(c.x)), static_cast<long>(std::floor(c.y)), static_cast<long>(std::floor(c.z))};
    }
    static std::uint64_t key(long x, long y, long z) {
        // 21 bits per axis; the grid spans at most 2^21 cells per axis (h ≥ extent / 2^20).
        const auto u = [](long v) { return static_cast<std::uint64_t>(v) & 0x1FFFFFu; };
        return u(x) | (u(y) << 21) | (u(z) << 42);
    }

    // Every patch whose bounding box may meet `box` (a superset, sorted, unique).
    void query(const Box& box, std::vector<std::uint32_t>& out) const {
        out.clear();
        const auto a = cell_of(box.lo), b = cell_of(box.hi);
        const long count = (b[0] - a[0] + 1) * (b[1] - a[1] + 1) * (b[2] - a[2] + 1);
        if (count > kMaxCellsPerQuery) {
            for (std::uint32_t q = 0; q < boxes.size(); ++q)
                if (boxes[q].overlaps(box)) out.push_back(q);
            return;
        }
        for (long x = a[0]; x <= b[0]; ++x)
            for (long y = a[1]; y <= b[1]; ++y)
                for (long z = a[2]; z <= b[2]; ++z) {
                    const auto it = cells.find(key(x, y, z));
                    if (it == cells.end()) continue;
                    for (std::uint32_t q : it->second)
                        if (boxes[q].overlaps(box)) out.push_back(q);
                }
        std::sort(out.begin(), out.end());
        out.erase(std::unique(out.begin(), out.end()), out.end());
    }

    Impl(const Scene& s, const NearFieldOptions& o) : scene(s), options(o) {
        const std::size_t n = s.size();
        polys.resize(n);
        boxes.resize(n);
        radius.resize(n);
        std::vector<double> sizes(n);
        for (std::size_t i = 0; i < n; ++i) {
            const Patch& p = s.patches[i];
            polys[i].n = p.count;
            for (std::size_t k = 0; k < p.count; ++k) polys[i].v[k] = s.positions[p.v[k]];
            Box b{polys[i].v[0], polys[i].v[0]};
            for (std::size_t k = 1; k < p.count; ++k) {
                b.lo = glm::min(b.lo, polys[i].v[k]);
                b.hi = glm::max(b.hi, polys[i].v[k]);
            }
            boxes[i] = b;
            for (std::size_t k = 0; k < p.count; ++k)
                radius[i] = std::max(radius[i], glm::length(polys[i].v[k] - p.centroid));
            sizes[i] = p.size;
            max_size = std::max(max_size, p.size);
        }
        if (n == 0) return;
        // Cell side: the median patch size (most patches then fall in a few cells), but no finer
        // than 2^-20 of the extent so that cell coordinates fit the hash key.
        std::nth_element(sizes.begin(), sizes.begin() + static_cast<long>(n / 2), sizes.end());
        h = std::max({sizes[n / 2], s.extent() * std::ldexp(1.0, -20), 1e-300});
        origin = s.bbox_min - Vec3(h);
        for (std::uint32_t i = 0; i < n; ++i) {
            const auto a = cell_of(boxes[i].lo), b = cell_of(boxes[i].hi);
            const long count = (b[0] - a[0] + 1) * (b[1] - a[1] + 1) * (b[2] - a[2] + 1);
            if (count > kMaxCellsPerQuery) {
                // A patch far larger than the median would fill thousands of cells: it goes on a
                // list that every query scans instead.
                big.push_back(i);
                continue;
            }
            for (long x = a[0]; x <= b[0]; ++x)
                for (long y = a[1]; y <= b[1]; ++y)
                    for (long z = a[2]; z <= b[2]; ++z) cells[key(x, y, z)].push_back(i);
        }
    }

    void query_all(const Box& box, std::vector<std::uint32_t>& out) const {
        query(box, out);
        bool added = false;
        for (std::uint32_t q : big)
            if (boxes[q].overlaps(box)) {
                out.push_back(q);
                added = true;
            }
        if (added) {
            std::sort(out.begin(), out.end());
            out.erase(std::unique(out.begin(), out.end()), out.end());
        }
    }

    bool unoccluded(std::uint32_t i, std::uint32_t j) const;

    // Far field (NearFieldOptions::far_field): the planes of the scene's patches
    // (unoriented; a two-sided plate's sides share one), per patch two bit sets over them
    // (a vertex strictly in front of / behind the plane), and its 2 × 2 and 3 × 3 quadrature rules.
    struct Plane {
        Vec3 n{0.0};
        double d = 0;
        double thickness = 0;  // largest distance of a member's vertex from the plane
        Box box;               // of the members
        std::vector<std::uint32_t> members;
    };
    static constexpr std::size_t kMaxPlanes = 256;
    std::vector<Plane> planes;
    std::size_t words = 0;  // 64-bit words per patch in plus_bits / minus_bits
    std::vector<std::uint64_t> plus_bits, minus_bits;
    double far_tol = 0;
    // Per patch, its 2 × 2 (index 0) and 3 × 3 (index 1) quadrature rule (3 and 9 points on a
    // triangle: geometry/quadrature.hpp).
    struct Rule {
        std::array<Vec3, 9> p{};
        std::array<double, 9> w{};
        std::uint8_t n = 0;
    };
    std::vector<std::array<Rule, 2>> rules;

    std::string far_status;
    double far_cost = NAN;
    void build_far_field();
    double estimate_far_cost(double& complete_fraction) const;
    double far_complete = NAN;  // estimated share of rows the far field makes complete
    bool section_meets(std::uint32_t i, std::uint32_t j, std::size_t g, const Box& pair) const;
    bool far_unoccluded(std::uint32_t i, std::uint32_t j) const;
    bool facing(std::uint32_t i, std::uint32_t j) const;
    std::pair<double, double> far_value(std::uint32_t i, std::uint32_t j, double d) const;
};

// How a far pair's value is integrated, by centroid distance d in sizes (the larger of the
// pair's longest edges): the exact receiver (Lambert's contour) and a 3 × 3 sender rule below
// kFarPoint3K, the point kernel cosθ_i cosθ_j / (π r²) on 3 × 3 points of each patch below
// kFarPoint2K, on 2 × 2 points of each beyond. Relative errors measured against the contour
// integral (unit squares parallel, perpendicular on a common plane, tilted): Lambert 3 × 3 ≤ 7e-6
// at 3 sizes; point 3 × 3 ≤ 3.5e-6 at 4 sizes, 1.7e-7 at 6; point 2 × 2 ≤ 1.1e-5 at 12 sizes,
// 1.4e-6 at 20. Errors fall as (h/d)⁶ and (h/d)⁴: the bounds below are those, with margin.
// Lambert's contour costs an atan2 per edge per point; the point kernel a few flops per pair of
// points: 9 contours cost about as much as 300 kernel evaluations. At kFarPoint1K sizes and
// beyond, one point per patch (the centroids) is enough: the midpoint rule's relative error is
// (2/3)(h/d)² for squares face to face (the offset ρ between a point of each has ⟨ρ²⟩ = h²/3 and
// the kernel falls as 1 − 2ρ²/d²; tests/accuracy/test_far_field.cpp), 1.6e-6 there; bounded by
// (h/d)².
constexpr double kFarPoint3K = 5.0;
constexpr double kFarPoint2K = 16.0;
constexpr double kFarPoint1K = 640.0;

// Cost model of the far field on one core (ns), calibrated with tools/bench_far_field on these
// machines (docs/benchmarks.md): per candidate patch (distance, facing and plane tests), and per
// entry by its rule: 9 Lambert contours, 81, 16 or 1 kernel evaluations; per plane whose section
// by the pair's hull must be examined (or is rejected at once: the pair's box misses the
// plane's members).
constexpr double kCostCandidate = 12, kCostLambert3 = 1000, kCostPoint3 = 250, kCostPoint2 = 50, kCostPoint1 = 7,
                 kCostSection = 100, kCostSectionReject = 5;
constexpr std::size_t kCostSampleRows = 64;

// The far field's cost per row, estimated from up to kCostSampleRows rows spread over the scene:
// for each, the facing pairs beyond the near range by rule (visibility assumed proven: an upper
// bound), and whether the row would be complete (every near pair proven by the shaft test and
// every far one by the plane test: not rendered at all). Deterministic: a function of the
// geometry only.
double NearFieldCorrector::Impl::estimate_far_cost(double& complete_fraction) const {
    const std::size_t n = scene.size();
    const std::size_t rows = std::min(n, kCostSampleRows);
    double total = 0;
    std::size_t complete = 0;
    for (std::size_t r = 0; r < rows; ++r) {
        const auto i = static_cast<std::uint32_t>(r * n / rows);
        const Patch& pi = scene.patches[i];
        double cost = kCostCandidate * static_cast<double>(n);
        bool known = true;  // every facing pair proven: the row would not be rendered
        for (std::uint32_t j = 0; j < n; ++j) {
            if (j == i) continue;
            const Patch& pj = scene.patches[j];
            const double size = std::max(pi.size, pj.size);
            const double d = glm::length(pj.centroid - pi.centroid);
            if (!facing(i, j)) continue;
            if (d < options.k * size) {
                if (known) known = unoccluded(i, j);
                continue;
            }
            const Box pair{glm::min(boxes[i].lo, boxes[j].lo), glm::max(boxes[i].hi, boxes[j].hi)};
            for (std::size_t w = 0; w < words; ++w) {
                std::uint64_t c = (plus_bits[i * words + w] | plus_bits[j * words + w]) &
                                  (minus_bits[i * words + w] | minus_bits[j * words + w]);
                for (; c; c &= c - 1)
                    cost += pair.overlaps(planes[w * 64 + static_cast<std::size_t>(std::countr_zero(c))].box)
                                ? kCostSection
                                : kCostSectionReject;
            }
            cost += d < kFarPoint3K * size   ? kCostLambert3
                    : d < kFarPoint2K * size ? kCostPoint3
                    : d < kFarPoint1K * size ? kCostPoint2
                                             : kCostPoint1;
            if (known) known = far_unoccluded(i, j);
        }
        total += cost;
        complete += known;
    }
    complete_fraction = static_cast<double>(complete) / static_cast<double>(rows);
    return total / static_cast<double>(rows);
}

void NearFieldCorrector::Impl::build_far_field() {
    using FarField = NearFieldOptions::FarField;
    const std::size_t n = scene.size();
    if (options.far_field == FarField::off) {
        far_status = "off";
        return;
    }
    if (n == 0) {
        far_status = "off: no patches";
        return;
    }
    if (options.far_field == FarField::automatic) {
        // Every row examines every patch: a scene too large for even that is off unmeasured
        // (even if every row then needed no measurement, saving a whole row of the inner
        // provider).
        const double floor = kCostCandidate * static_cast<double>(n);
        if (floor > options.far_field_budget_ns + options.far_field_row_ns) {
            far_status = fmt::format("off: {} patches, at least {:.3g} ms per row, over the budget of {:.3g} ms", n,
                                     floor * 1e-6, (options.far_field_budget_ns + options.far_field_row_ns) * 1e-6);
            return;
        }
    }
    const double coord = std::max({std::abs(scene.bbox_min.x), std::abs(scene.bbox_min.y), std::abs(scene.bbox_min.z),
                                   std::abs(scene.bbox_max.x), std::abs(scene.bbox_max.y), std::abs(scene.bbox_max.z)});
    // In a plane: within 1e-9 of the scene's extent, plus the rounding of far-off coordinates (as
    // plane_tolerance above).
    far_tol = 1e-9 * scene.extent() + 16 * std::numeric_limits<double>::epsilon() * coord;
    for (std::uint32_t i = 0; i < n; ++i) {
        const Patch& p = scene.patches[i];
        Vec3 nc = p.normal;  // unoriented: the largest component positive
        const Vec3 a = glm::abs(nc);
        const int axis = a.x >= a.y && a.x >= a.z ? 0 : a.y >= a.z ? 1 : 2;
        if (nc[axis] < 0) nc = -nc;
        std::size_t found = planes.size();
        for (std::size_t g = 0; g < planes.size() && found == planes.size(); ++g) {
            if (!(glm::dot(nc, planes[g].n) > 1.0 - 1e-9)) continue;
            bool in = true;
            for (std::size_t k = 0; k < polys[i].n && in; ++k)
                in = std::abs(glm::dot(planes[g].n, polys[i].v[k]) - planes[g].d) <= far_tol;
            if (in) found = g;
        }
        if (found == planes.size()) {
            if (planes.size() == kMaxPlanes) {  // curved or cluttered: the far field stays off
                planes.clear();
                far_status = fmt::format("off: more than {} planes", kMaxPlanes);
                return;
            }
            planes.push_back(Plane{nc, glm::dot(nc, p.centroid), 0, boxes[i], {}});
        }
        Plane& g = planes[found];
        g.box.lo = glm::min(g.box.lo, boxes[i].lo);
        g.box.hi = glm::max(g.box.hi, boxes[i].hi);
        g.members.push_back(i);
        for (std::size_t k = 0; k < polys[i].n; ++k)
            g.thickness = std::max(g.thickness, std::abs(glm::dot(g.n, polys[i].v[k]) - g.d));
    }
    words = (planes.size() + 63) / 64;
    plus_bits.assign(n * words, 0);
    minus_bits.assign(n * words, 0);
    for (std::uint32_t i = 0; i < n; ++i)
        for (std::size_t g = 0; g < planes.size(); ++g) {
            const Plane& P = planes[g];
            // A plane whose members are not flat to far_tol (a warped quad) is a slab: a vertex
            // inside it counts as on both sides, so any pair near it is tested (and refused).
            const double lim = P.thickness > far_tol ? P.thickness + far_tol : far_tol;
            const bool thick = P.thickness > far_tol;
            for (std::size_t k = 0; k < polys[i].n; ++k) {
                const double s = glm::dot(P.n, polys[i].v[k]) - P.d;
                const bool above = s > lim || (thick && s >= -lim);
                const bool below = s < -lim || (thick && s <= lim);
                if (above) plus_bits[i * words + g / 64] |= std::uint64_t{1} << (g % 64);
                if (below) minus_bits[i * words + g / 64] |= std::uint64_t{1} << (g % 64);
            }
        }
    if (options.far_field == FarField::automatic) {
        // The budget, plus what rows made complete save: they are not measured at all.
        far_cost = estimate_far_cost(far_complete);
        const double budget = options.far_field_budget_ns + far_complete * options.far_field_row_ns;
        if (far_cost > budget) {
            far_status = fmt::format("off: estimated {:.3g} ms per row, over the budget of {:.3g} ms ({:.0f}% of rows "
                                     "complete)",
                                     far_cost * 1e-6, budget * 1e-6, 100 * far_complete);
            planes.clear();
            plus_bits.clear();
            minus_bits.clear();
            return;
        }
    }
    rules.resize(n);
    std::vector<Vec3> pts;
    std::vector<double> wts;
    for (std::uint32_t i = 0; i < n; ++i)
        for (int r = 0; r < 2; ++r) {
            patch_quadrature(polys[i].span(), 2 + r, pts, wts);
            Rule& rule = rules[i][static_cast<std::size_t>(r)];
            rule.n = static_cast<std::uint8_t>(pts.size());
            for (std::size_t k = 0; k < pts.size(); ++k) {
                rule.p[k] = pts[k];
                rule.w[k] = wts[k];
            }
        }
    far_status = std::isnan(far_cost)
                     ? fmt::format("on: {} planes", planes.size())
                     : fmt::format("on: {} planes, estimated {:.3g} ms per row, budget {:.3g} ms ({:.0f}% of rows "
                                   "complete)",
                                   planes.size(), far_cost * 1e-6,
                                   (options.far_field_budget_ns + far_complete * options.far_field_row_ns) * 1e-6,
                                   100 * far_complete);
}

// Whether some patch of plane g other than i and j may meet the section of hull(i ∪ j) by that
// plane (conservatively: bounding boxes). The section of a convex hull by a plane is the convex
// hull of the hull's vertices in the plane and of the points where segments between vertices on
// opposite sides cross it.
bool NearFieldCorrector::Impl::section_meets(std::uint32_t i, std::uint32_t j, std::size_t g, const Box& pair) const {
    const Plane& P = planes[g];
    if (P.thickness > far_tol) return true;
    // The section lies in the hull, so in the pair's bounding box: a plane whose members' box
    // misses that box blocks nothing (most conflicts in a room: a block's face plane cuts the
    // room, its face does not come near the pair).
    if (!pair.overlaps(P.box)) return false;
    std::array<Vec3, 8> v{};
    std::array<double, 8> s{};
    std::size_t m = 0;
    for (std::size_t k = 0; k < polys[i].n; ++k) v[m++] = polys[i].v[k];
    for (std::size_t k = 0; k < polys[j].n; ++k) v[m++] = polys[j].v[k];
    for (std::size_t k = 0; k < m; ++k) s[k] = glm::dot(P.n, v[k]) - P.d;
    Box sec{Vec3(INFINITY), Vec3(-INFINITY)};
    const auto add = [&](const Vec3& x) {
        sec.lo = glm::min(sec.lo, x);
        sec.hi = glm::max(sec.hi, x);
    };
    for (std::size_t a = 0; a < m; ++a) {
        if (std::abs(s[a]) <= far_tol) add(v[a]);
        for (std::size_t b = 0; b < m; ++b)
            if (s[a] > far_tol && s[b] < -far_tol) add(v[a] + (v[b] - v[a]) * (s[a] / (s[a] - s[b])));
    }
    sec.lo -= Vec3(2 * far_tol);
    sec.hi += Vec3(2 * far_tol);
    if (!sec.overlaps(P.box)) return false;
    for (std::uint32_t q : P.members)
        if (q != i && q != j && boxes[q].overlaps(sec)) return true;
    return false;
}

// A segment from a point of i to a point of j meets a plane only where the two lie on opposite
// sides of it (or in it: touching, measure zero, as for the shaft test). So patches of a plane
// that no segment crosses block nothing, and where segments cross it, only members that meet the
// crossing region can.
bool NearFieldCorrector::Impl::far_unoccluded(std::uint32_t i, std::uint32_t j) const {
    if (planes.empty()) return false;
    const std::uint64_t* pi = &plus_bits[i * words];
    const std::uint64_t* pj = &plus_bits[j * words];
    const std::uint64_t* mi = &minus_bits[i * words];
    const std::uint64_t* mj = &minus_bits[j * words];
    // The pair's bounding box, widened by the tolerance of touching.
    const Box pair{glm::min(boxes[i].lo, boxes[j].lo) - Vec3(2 * far_tol), glm::max(boxes[i].hi, boxes[j].hi) + Vec3(2 * far_tol)};
    for (std::size_t w = 0; w < words; ++w) {
        std::uint64_t c = (pi[w] | pj[w]) & (mi[w] | mj[w]);
        while (c) {
            const std::size_t g = w * 64 + static_cast<std::size_t>(std::countr_zero(c));
            c &= c - 1;
            if (section_meets(i, j, g, pair)) return false;
        }
    }
    return true;
}

// Facing: some vertex of each farther than plane_tolerance in front of the other's plane (a
// polygon within it is seen edge-on; coplanar neighbours must not count as facing).
bool NearFieldCorrector::Impl::facing(std::uint32_t i, std::uint32_t j) const {
    const Patch& pi = scene.patches[i];
    const Patch& pj = scene.patches[j];
    const double tol = 2 * plane_tolerance(pi, pj);
    const Poly& qi = polys[i];
    const Poly& qj = polys[j];
    double front_j = -INFINITY, front_i = -INFINITY;
    for (std::size_t v = 0; v < qj.n; ++v) front_j = std::max(front_j, glm::dot(pi.normal, qj.v[v] - pi.centroid));
    for (std::size_t v = 0; v < qi.n; ++v) front_i = std::max(front_i, glm::dot(pj.normal, qi.v[v] - pj.centroid));
    return front_j > tol && front_i > tol;
}

// F_ij of an unoccluded pair beyond the near range (see kFarPoint3K) and a bound on its error.
std::pair<double, double> NearFieldCorrector::Impl::far_value(std::uint32_t i, std::uint32_t j, double d) const {
    const Patch& pi = scene.patches[i];
    const Patch& pj = scene.patches[j];
    const double size = std::max(pi.size, pj.size);
    const double h2 = (size / d) * (size / d);
    if (d >= kFarPoint1K * size) {
        const Vec3 r = pj.centroid - pi.centroid;
        const double r2 = glm::dot(r, r);
        const double f = std::max(0.0, glm::dot(pi.normal, r)) * std::max(0.0, -glm::dot(pj.normal, r)) / (r2 * r2) *
                         pj.area / std::numbers::pi;
        return {f, f * h2};
    }
    if (d >= kFarPoint3K * size) {
        const bool fine = d < kFarPoint2K * size;
        const Rule& a = rules[i][fine];
        const Rule& b = rules[j][fine];
        double f = 0;
        for (std::size_t s = 0; s < a.n; ++s) {
            double g = 0;
            for (std::size_t t = 0; t < b.n; ++t) {
                const Vec3 r = b.p[t] - a.p[s];
                const double r2 = glm::dot(r, r);
                g += b.w[t] * std::max(0.0, glm::dot(pi.normal, r)) * std::max(0.0, -glm::dot(pj.normal, r)) / (r2 * r2);
            }
            f += a.w[s] * g;
        }
        f *= pj.area / std::numbers::pi;
        // 1.1e-5 = 0.23 h⁴ at 12 sizes; 3.5e-6 = 0.015 h⁶ at 4 sizes.
        return {f, f * (fine ? 0.05 * h2 * h2 * h2 : 0.5 * h2 * h2)};
    }
    const auto poly = polys[j].span();
    const Rule& a = rules[i][1];
    double f = 0;
    for (std::size_t s = 0; s < a.n; ++s) {
        const Vec3& x = a.p[s];
        if (!(glm::dot(x - pj.centroid, pj.normal) > 0)) continue;  // behind j: sees its back
        bool whole = true;
        for (const Vec3& v : poly) whole = whole && glm::dot(v - x, pi.normal) > 0;
        f += a.w[s] * (whole ? ff_point_polygon_unclipped(x, pi.normal, poly) : ff_point_polygon(x, pi.normal, poly));
    }
    return {f, f * 0.05 * h2 * h2 * h2};  // 7e-6 = 0.005 h⁶ at 3 sizes
}

// Separating-axis test between the convex hull of patches i ∪ j and each other patch q whose
// bounding box meets the pair's. Candidate axes: the normals of q, i and j; the cross products of
// q's edges with every segment between two hull points (the edge–edge axes of the full test);
// and the normals of every plane through three hull points (the hull's face planes are among
// them). Touching (interval overlap ≤ tol) counts as separated: see the header for why that
// blocks nothing. A missed separating axis can only make the test refuse.
bool NearFieldCorrector::Impl::unoccluded(std::uint32_t i, std::uint32_t j) const {
    std::array<Vec3, 8> hull{};
    std::size_t m = 0;
    for (std::size_t k = 0; k < polys[i].n; ++k) hull[m++] = polys[i].v[k];
    for (std::size_t k = 0; k < polys[j].n; ++k) hull[m++] = polys[j].v[k];
    Box pair{glm::min(boxes[i].lo, boxes[j].lo), glm::max(boxes[i].hi, boxes[j].hi)};
    const double scale = glm::length(pair.hi - pair.lo);
    // Relative tolerance of touching: a q that enters the hull by less than 1e-9 of the pair's
    // size blocks at most a sliver of that relative width (documented in docs/accuracy.md).
    const double tol = 1e-9 * scale;
    const Box inflated{pair.lo - Vec3(tol), pair.hi + Vec3(tol)};
    std::vector<std::uint32_t> candidates;
    query_all(inflated, candidates);

    // Hull-only axes are the same for every q: precompute them.
    std::vector<Vec3> axes{scene.patches[i].normal, scene.patches[j].normal};
    for (std::size_t a = 0; a < m; ++a)
        for (std::size_t b = a + 1; b < m; ++b)
            for (std::size_t c = b + 1; c < m; ++c) {
                const Vec3 nrm = glm::cross(hull[b] - hull[a], hull[c] - hull[a]);
                if (glm::dot(nrm, nrm) > 1e-24 * scale * scale * scale * scale) axes.push_back(glm::normalize(nrm));
            }
    std::vector<Vec3> seg;
    for (std::size_t a = 0; a < m; ++a)
        for (std::size_t b = a + 1; b < m; ++b) seg.push_back(hull[b] - hull[a]);

    auto separated = [&](const Vec3& axis, const Poly& q) {
        double hlo = INFINITY, hhi = -INFINITY, qlo = INFINITY, qhi = -INFINITY;
        for (std::size_t k = 0; k < m; ++k) {
            const double d = glm::dot(axis, hull[k]);
            hlo = std::min(hlo, d);
            hhi = std::max(hhi, d);
        }
        for (std::size_t k = 0; k < q.n; ++k) {
            const double d = glm::dot(axis, q.v[k]);
            qlo = std::min(qlo, d);
            qhi = std::max(qhi, d);
        }
        return hhi <= qlo + tol || qhi <= hlo + tol;
    };

    for (std::uint32_t qi : candidates) {
        if (qi == i || qi == j) continue;
        const Poly& q = polys[qi];
        bool sep = separated(scene.patches[qi].normal, q);
        for (std::size_t a = 0; !sep && a < axes.size(); ++a) sep = separated(axes[a], q);
        for (std::size_t e = 0; !sep && e < q.n; ++e) {
            const Vec3 edge = q.v[(e + 1) % q.n] - q.v[e];
            for (std::size_t s = 0; !sep && s < seg.size(); ++s) {
                const Vec3 axis = glm::cross(edge, seg[s]);
                const double len2 = glm::dot(axis, axis);
                if (len2 <= 1e-24 * scale * scale * scale * scale) continue;
                sep = separated(axis / std::sqrt(len2), q);
            }
        }
        if (!sep) return false;
    }
    return true;
}

NearFieldCorrector::NearFieldCorrector(const Scene& scene, const NearFieldOptions& options) {
    if (!(options.k > 0) || !std::isfinite(options.k))
        throw InputError(fmt::format("near-field correction: k = {} must be a positive number", options.k));
    impl_ = std::make_unique<Impl>(scene, options);
    impl_->build_far_field();
}

NearFieldOptions near_field_options_for_hemicube(int resolution, double k) {
    NearFieldOptions o;
    o.k = k;
    o.sender_quadrature = true;
    const double n = resolution;
    o.pixel_delta_ff = 4.0 / (std::numbers::pi * n * n);
    // 30% of a hemicube row: 3N² pixels at about 5 ns each on one core of llvmpipe
    // (tools/bench_far_field prints both per row; docs/benchmarks.md).
    o.far_field = NearFieldOptions::FarField::automatic;
    o.far_field_row_ns = 3.0 * n * n * 5.0;
    o.far_field_budget_ns = 0.3 * o.far_field_row_ns;
    return o;
}

bool NearFieldCorrector::far_unoccluded(std::uint32_t i, std::uint32_t j) const { return impl_->far_unoccluded(i, j); }

std::size_t NearFieldCorrector::far_field_planes() const { return impl_->planes.size(); }
const std::string& NearFieldCorrector::far_field_status() const { return impl_->far_status; }
double NearFieldCorrector::far_field_cost_ns() const { return impl_->far_cost; }

NearFieldCorrector::~NearFieldCorrector() = default;

bool NearFieldCorrector::provably_unoccluded(std::uint32_t i, std::uint32_t j) const { return impl_->unoccluded(i, j); }

void NearFieldCorrector::analyse(std::uint32_t i, NearAnalysis& out) const {
    const Impl& im = *impl_;
    out = NearAnalysis{};
    Stopwatch watch;
    const Patch& pi = im.scene.patches[i];
    const double k = im.options.k;
    const double reach = k * std::max(pi.size, im.max_size);
    std::vector<std::uint32_t> near;
    im.query_all(Box{pi.centroid - Vec3(reach), pi.centroid + Vec3(reach)}, near);
    for (std::uint32_t j : near) {
        if (j == i) continue;
        const Patch& pj = im.scene.patches[j];
        const double d = glm::length(pj.centroid - pi.centroid);
        if (d >= k * std::max(pi.size, pj.size)) continue;
        if (!im.facing(i, j)) continue;
        ++out.near_pairs;
        if (!im.unoccluded(i, j)) {
            ++out.refused;
            continue;
        }
        const double gap = d - im.radius[i] - im.radius[j];
        if (gap >= 2 * std::min(im.radius[i], im.radius[j])) {
            const double f = separated_ff(im.polys[i], pi, im.radius[i], im.polys[j], pj, im.radius[j]);
            out.exact.emplace_back(j, f);
            out.far_error += 1e-9 * f;  // the 6 × 6 rule's measured worst, 3.6e-10, with margin
        } else {
            out.exact.emplace_back(j, exact_ff(im.polys[i], pi, im.polys[j], pj));
        }
    }
    if (!im.planes.empty()) {
        // Far field: every other facing pair the plane test proves unoccluded.
        out.far = true;
        std::vector<std::pair<std::uint32_t, double>> far;
        const auto n = static_cast<std::uint32_t>(im.scene.size());
        for (std::uint32_t j = 0; j < n; ++j) {
            if (j == i) continue;
            const Patch& pj = im.scene.patches[j];
            const double d = glm::length(pj.centroid - pi.centroid);
            if (d < k * std::max(pi.size, pj.size) || !im.facing(i, j)) continue;
            if (!im.far_unoccluded(i, j)) {
                ++out.far_unproven;
                continue;
            }
            const auto [f, error] = im.far_value(i, j, d);
            far.emplace_back(j, f);
            out.far_error += error;
        }
        out.far_entries = far.size();
        out.complete = out.refused == 0 && out.far_unproven == 0;
        std::vector<std::pair<std::uint32_t, double>> merged(out.exact.size() + far.size());
        std::merge(out.exact.begin(), out.exact.end(), far.begin(), far.end(), merged.begin());
        out.exact = std::move(merged);
    }
    out.seconds = watch.seconds();
    out.done = true;
}

void NearFieldCorrector::correct(std::uint32_t i, SparseRow& row, NearFieldStats& stats, double* error_estimate,
                                 const NearAnalysis* analysis, bool sampled_row) const {
    const Impl& im = *impl_;
    ++stats.rows;
    const Patch& pi = im.scene.patches[i];
    const double k = im.options.k;
    NearAnalysis local;
    if (!analysis || !analysis->done) {
        analyse(i, local);
        analysis = &local;
    }
    const auto& exact = analysis->exact;  // (j, exact F_ij), j increasing
    stats.near_pairs += analysis->near_pairs;
    stats.refused += analysis->refused;
    stats.far_rows += analysis->far;
    stats.far_entries += analysis->far_entries;
    stats.far_unproven += analysis->far_unproven;
    stats.rows_analytic += analysis->skipped;
    stats.near_seconds += analysis->seconds;
    Stopwatch quadrature_watch;
    if (sampled_row) ++stats.rows_sampled;
    // A sampled row is already the 2 × 2 sender quadrature (sub-hemicubes): no ratio on top.
    const bool quadrature = im.options.sender_quadrature && !sampled_row;
    const double inner_sum = row.sum();
    // Trigger for the sender quadrature: some entry within quadrature_k sizes (beyond, the
    // midpoint rule's relative error (h/d)²/24 is below 1e-5 and the entry is left as it is).
    // O(nnz) flops; a row that triggers nothing is handed on untouched.
    bool quadrature_needed = false;
    if (quadrature)
        for (std::uint32_t j : row.col) {
            const Patch& pj = im.scene.patches[j];
            const Vec3 r = pj.centroid - pi.centroid;
            const double lim = im.options.quadrature_k * std::max(pi.size, pj.size);
            if (glm::dot(r, r) < lim * lim) {
                quadrature_needed = true;
                break;
            }
        }
    // Per-entry error estimate (docs/accuracy.md, "Per-row error estimate"): a systematic part
    // by how the entry was made, plus the inner provider's noise.
    const auto midpoint_error = [&](std::uint32_t j, double f) {
        // The midpoint rule's relative error, (h_i/d)²/24 times a shape constant of at most ~2.
        const Vec3 r = im.scene.patches[j].centroid - pi.centroid;
        const double m = pi.size * pi.size / glm::dot(r, r) / 12.0;
        if (sampled_row) return f * m * m;  // the 2 × 2 rule's residual, about the square
        if (!quadrature) return 0.0;        // the inner provider samples the whole sender (ray caster)
        return f * m;
    };
    const auto noise = [&](double f) {
        double e = 0;
        if (im.options.pixel_delta_ff > 0) {
            // About 4√P pixels on the outline of a receiver covering P pixels, each off by a
            // uniform fraction of a pixel: σ = ΔF √(4√P / 12)... taken as ΔF √(4√P / 6) (the
            // pixels of an outline are not independent).
            const double dF = im.options.pixel_delta_ff;
            e += dF * std::sqrt(4.0 * std::sqrt(f / dF) / 6.0);
        }
        if (im.options.rays > 0) e += std::sqrt(f / im.options.rays);
        return e;
    };
    // Detection only: receivers worth fewer than 4 of the largest hemicube pixels are found only
    // by the few pixels they happen to cover (no correction for them yet; docs/accuracy.md).
    if (im.options.pixel_delta_ff > 0) {
        std::uint64_t small = 0;
        for (const double f : row.val) small += f < 4 * im.options.pixel_delta_ff;
        stats.small_receiver_entries += small;
        stats.rows_with_small_receivers += small > 0;
    }
    double estimate = analysis->far_error;
    if (exact.empty() && !quadrature_needed) {
        ++stats.rows_untouched;
        if (error_estimate) {
            for (std::size_t a = 0; a < row.nnz(); ++a) estimate += midpoint_error(row.col[a], row.val[a]) + noise(row.val[a]);
            *error_estimate = estimate;
        }
        stats.quadrature_seconds += quadrature_watch.seconds();
        return;
    }
    if (!exact.empty()) ++stats.rows_touched;
    if (quadrature_needed) ++stats.rows_quadrature;
    stats.replaced += exact.size();
    // Sender quadrature rule on patch i (see NearFieldOptions).
    std::vector<Vec3> qp;
    std::vector<double> qw;
    if (quadrature_needed) patch_quadrature(im.polys[i].span(), 2, qp, qw);
    const std::size_t nq = qp.size();
    // Beyond this many sizes the quadrature ratio uses the point kernel cosθ_i cosθ_j / r⁴ (see
    // below): its relative error on the correction is about (size_j/d)² ≤ 1/36 at 6 sizes, where
    // the correction itself is ≈ (size_i/d)²/24 ≤ 1e-3 of F_ij: 3e-5 of F_ij.
    constexpr double kPointKernelK = 6.0;
    // The quadrature ratio is a small correction where the midpoint rule is sound. A ratio far
    // from 1 means j straddles i's horizon or the centre sees little of it (the hemicube's value
    // is then pixels at a grazing angle, not a midpoint value): scaling it would amplify pixel
    // error (rows of the Cornell box grew to 1.098). Such entries are left alone.
    constexpr double kMaxRatioChange = 0.25;
    double systematic = 0;  // of the entry rescale() just made
    auto ratio = [&](double f, double r) {
        if (!(std::abs(r - 1.0) <= kMaxRatioChange)) {
            systematic = std::abs(r - 1.0) * f;  // left alone: off by about the ratio it needed
            return f;
        }
        ++stats.quadrature;
        // What remains is the 2 × 2 rule's error, O((h/d)⁴): the square of the midpoint one.
        const double m = std::abs(r - 1.0);
        systematic = f * r * m * m;
        return f * r;
    };
    auto rescale = [&](std::uint32_t j, double f) {
        systematic = midpoint_error(j, f);
        if (!quadrature_needed) return f;
        const Patch& pj = im.scene.patches[j];
        const double d = glm::length(pj.centroid - pi.centroid);
        const double size = std::max(pi.size, pj.size);
        if (d >= im.options.quadrature_k * size) return f;
        // Near pairs were replaced or refused above: a refused one may be occluded, and its
        // hemicube value is kept as it is (the midpoint rule's error there reaches ~5%: the
        // issue's −4.7% on squares sharing an edge).
        if (d < k * size) {
            systematic = 0.05 * f;
            return f;
        }
        if (d >= kPointKernelK * size) {
            // Far: the receiver as a point at its centroid (see kPointKernelK); a few flops per
            // point instead of Lambert's contour.
            auto kernel = [&](const Vec3& x) {
                const Vec3 r = pj.centroid - x;
                const double r2 = glm::dot(r, r);
                return std::max(0.0, glm::dot(pi.normal, r)) * std::max(0.0, -glm::dot(pj.normal, r)) / (r2 * r2);
            };
            const double mid = kernel(pi.centroid);
            if (!(mid > 0)) return f;
            double q = 0;
            for (std::size_t k2 = 0; k2 < nq; ++k2) q += qw[k2] * kernel(qp[k2]);
            return ratio(f, q / mid);
        }
        const auto poly = im.polys[j].span();
        // Lambert's contour; without clipping or checks when all of j is in front of the plane
        // through x (then nothing needs clipping), which is nearly always the case here.
        const auto lambert = [&](const Vec3& x) {
            for (const Vec3& v : poly)
                if (!(glm::dot(v - x, pi.normal) > 0)) return ff_point_polygon(x, pi.normal, poly);
            return ff_point_polygon_unclipped(x, pi.normal, poly);
        };
        const double mid = lambert(pi.centroid);
        if (!(mid > 0)) return f;  // the inner provider saw j where the centre sees it edge-on: keep
        double q = 0;
        // One-sided: points behind j's plane (a patch that j stands on, cut by j's base) see its
        // back, which ff_point_polygon would count.
        for (std::size_t k2 = 0; k2 < nq; ++k2)
            if (glm::dot(qp[k2] - pj.centroid, pj.normal) > 0)
                q += qw[k2] * lambert(qp[k2]);
        return ratio(f, q / mid);
    };
    // Merge: the replaced columns take their exact value (dropped when it is 0), others stay.
    SparseRow out;
    out.col.reserve(row.nnz() + exact.size());
    out.val.reserve(row.nnz() + exact.size());
    std::vector<std::uint8_t> is_exact;
    is_exact.reserve(row.nnz() + exact.size());
    std::size_t a = 0, b = 0;
    while (a < row.nnz() || b < exact.size()) {
        if (b == exact.size() || (a < row.nnz() && row.col[a] < exact[b].first)) {
            const double f = rescale(row.col[a], row.val[a]);
            estimate += systematic + noise(row.val[a]);
            if (f > 0) {
                out.col.push_back(row.col[a]);
                out.val.push_back(f);
                is_exact.push_back(0);
            }
            ++a;
            continue;
        }
        if (a < row.nnz() && row.col[a] == exact[b].first) ++a;
        if (exact[b].second > 0) {
            out.col.push_back(exact[b].first);
            out.val.push_back(exact[b].second);
            is_exact.push_back(1);
        }
        ++b;
    }
    // Closed rows stay closed. When the inner row sums to 1 (the centre saw only front faces:
    // no miss, no back face), so does the exact row of a patch in a closed scene: every point of
    // the patch sees surfaces all round. Near values that are exact and far values rescaled
    // from aliased pixels (thin slivers seen at grazing angles cover 0 or 3× their share of
    // pixels) no longer add up to it (up to 1.6e-3 off in a 24 × 24-per-wall box). The far
    // (non-exact) entries then share one factor that restores the sum; exact entries stay exact.
    // Likewise no row may sum above 1 (energy leaving i cannot arrive more than once): an open
    // row that the correction pushed above 1 gets the same treatment, down to 1.
    double fixed = 0, rest = 0;
    for (std::size_t e = 0; e < out.nnz(); ++e) (is_exact[e] ? fixed : rest) += out.val[e];
    // A row made without measuring is closed when its analytic sum is 1 within its values' own
    // error bounds (a patch that sees surfaces all round).
    const bool closed = analysis->skipped
                            ? std::abs(fixed + rest - 1.0) <= std::max(kClosedRowTolerance, 2 * analysis->far_error)
                            : std::abs(inner_sum - 1.0) <= kClosedRowTolerance;
    if (im.options.keep_closed_rows && (closed || fixed + rest > 1.0)) {
        // Normally the non-exact entries take the whole change. Where they are too few for that
        // (the far field made nearly all of the row exact: a factor beyond 1 ± 0.1 would be
        // pixel noise amplified), every entry shares it instead: the exact ones are then moved
        // by their own quadrature error's order (about 1e-5 relative).
        const double scale = (1.0 - fixed) / rest;
        const double all = 1.0 / (fixed + rest);
        const bool rest_only = rest > 0 && std::abs(scale - 1.0) <= 0.1;
        const double factor = rest_only ? scale : all;
        if (std::isfinite(factor) && std::abs(factor - 1.0) <= 0.1) {
            for (std::size_t e = 0; e < out.nnz(); ++e)
                if (!rest_only || !is_exact[e]) out.val[e] *= factor;
            ++(closed ? stats.rows_closed : stats.rows_capped);
            stats.closed_scale_max_change = std::max(stats.closed_scale_max_change, std::abs(factor - 1.0));
            estimate += std::abs(1.0 - factor) * (rest_only ? rest : fixed + rest);  // moved by this much
        }
    }
    if (error_estimate) *error_estimate = estimate;
    row = std::move(out);
    stats.quadrature_seconds += quadrature_watch.seconds();
}

CorrectedRowProvider::CorrectedRowProvider(const Scene& scene, RowProvider& inner, const NearFieldOptions& options)
    : inner_(inner), corrector_(scene, options), options_(options) {
    if (inner.size() != scene.size())
        throw InputError(fmt::format("near-field correction: the provider has {} rows, the scene {} patches", inner.size(),
                                     scene.size()));
}

void CorrectedRowProvider::compute_rows(std::span<const std::uint32_t> rows, const RowSink& sink) {
    // Near analysis per listed row, made when the inner provider asks whether to sample the row
    // (from its own threads: each slot is written once, by one of them, before its row exists)
    // or, failing that, when the row arrives.
    analyses_.assign(rows.size(), NearAnalysis{});
    std::size_t position = 0;
    const bool sample = options_.sub_hemicubes && inner_.can_sample_sender();
    const RowSink correct_row = [&](std::uint32_t i, const SparseRow& row) {
        Stopwatch watch;
        const std::size_t pos = position++;
        const NearAnalysis& a = analyses_[pos];
        // Whether light escapes, as measured: for a row not measured, its analytic sum.
        double measured = row.sum();
        if (a.skipped) {
            measured = 0;
            for (const auto& e : a.exact) measured += e.second;
        }
        stats_.inner_row_sum_min = std::min(stats_.inner_row_sum_min, measured);
        scratch_ = row;
        double estimate = 0;
        corrector_.correct(i, scratch_, stats_, &estimate, &a, sample && a.done && a.refused > 0);
        if (row_error_.size() != inner_.size()) row_error_.assign(inner_.size(), NAN);
        row_error_[i] = static_cast<float>(estimate);
        // Free the analysis: with the far field it holds up to a whole row, and every row of
        // the call has a slot (n² entries if none were freed: 225 MB for 3,744 patches).
        analyses_[pos] = NearAnalysis{};
        stats_.seconds += watch.seconds();
        sink(i, scratch_);
    };
    if (!sample) {
        inner_.compute_rows(rows, correct_row);
        return;
    }
    // Rows with a near pair that may be occluded are measured by sub-hemicubes at the sender's
    // quadrature points: the pair keeps a value with its own visibility and sender quadrature.
    inner_.compute_rows_sampled(
        rows,
        [&](std::size_t pos) {
            NearAnalysis& a = analyses_[pos];
            corrector_.analyse(rows[pos], a);
            if (a.refused > 0) return RowPlan::sampled;
            // Every facing pair known: nothing to measure (RowPlan::skip hands on an empty row).
            if (a.complete && options_.skip_complete_rows) {
                a.skipped = true;
                return RowPlan::skip;
            }
            return RowPlan::centre;
        },
        correct_row);
}

}  // namespace ffcube
