// The far field: planes, the plane-test visibility proof and the far values (see far_field.hpp).
#include "accuracy/far_field.hpp"

#include <fmt/format.h>
#include <glm/geometric.hpp>

#include <algorithm>
#include <bit>
#include <limits>
#include <numbers>

#include "ffcube/geometry/analytic.hpp"
#include "ffcube/geometry/quadrature.hpp"

#include "ffcube/geometry/tolerance.hpp"

namespace ffcube::accuracy {

FarField::FarField(const PatchSet& patches, const SpatialGrid& grid, const NearFieldOptions& options)
    : patches_(patches), grid_(grid), options_(options) {
    using Mode = NearFieldOptions::FarField;
    const Scene& scene = patches.scene;
    const std::size_t n = scene.size();
    if (options.far_field == Mode::off) {
        status_ = "off";
        return;
    }
    if (n == 0) {
        status_ = "off: no patches";
        return;
    }
    if (options.far_field == Mode::automatic) {
        // Every row examines every patch: a scene too large for even that is off unmeasured
        // (even if every row then needed no measurement, saving a whole row of the inner
        // provider).
        const double floor = far_field_cost_floor_ns(n);
        if (floor > options.far_field_budget_ns + options.far_field_row_ns) {
            status_ = fmt::format("off: {} patches, at least {:.3g} ms per row, over the budget of {:.3g} ms", n,
                                  floor * 1e-6, (options.far_field_budget_ns + options.far_field_row_ns) * 1e-6);
            return;
        }
    }
    const double coord = std::max({std::abs(scene.bbox_min.x), std::abs(scene.bbox_min.y), std::abs(scene.bbox_min.z),
                                   std::abs(scene.bbox_max.x), std::abs(scene.bbox_max.y), std::abs(scene.bbox_max.z)});
    // In a plane: within 1e-9 of the scene's extent, or the rounding of far-off coordinates if
    // larger (geometry/tolerance.hpp, as plane_tolerance).
    tol_ = geometric_tolerance(1e-9, scene.extent(), coord);
    if (!group_planes()) {  // curved or cluttered: the far field stays off
        planes_.clear();
        status_ = fmt::format("off: more than {} planes", kMaxPlanes);
        return;
    }
    mark_sides();
    if (options.far_field == Mode::automatic) {
        // The budget, plus what rows made complete save: they are not measured at all.
        cost_ = estimate_cost(complete_);
        const double budget = options.far_field_budget_ns + complete_ * options.far_field_row_ns;
        // Only the emitting rows (NearFieldOptions::far_field_emitters), when their cost fits
        // what the budget allows the whole run: n_E × cost ≤ n × budget.
        std::size_t emitting = 0;
        if (cost_ > budget && options.far_field_emitters) {
            only_.assign(n, 0);
            for (std::size_t i = 0; i < n; ++i) {
                const Vec3& e = scene.materials[scene.patches[i].material].ke;
                only_[i] = e.r > 0 || e.g > 0 || e.b > 0;
                emitting += only_[i];
            }
            if (emitting == 0 || static_cast<double>(emitting) * cost_ > static_cast<double>(n) * budget) {
                only_.clear();
                emitting = 0;
            }
        }
        if (emitting > 0) {
            only_rows_ = emitting;
            on_ = true;
            make_rules();
            status_ = fmt::format("on for the {} emitting rows only: estimated {:.3g} ms per row, over the budget of "
                                  "{:.3g} ms for every row ({:.0f}% of rows complete)",
                                  emitting, cost_ * 1e-6, budget * 1e-6, 100 * complete_);
            return;
        }
        if (cost_ > budget) {
            status_ = fmt::format("off: estimated {:.3g} ms per row, over the budget of {:.3g} ms ({:.0f}% of rows "
                                  "complete)",
                                  cost_ * 1e-6, budget * 1e-6, 100 * complete_);
            return;  // the planes stay, for senders cut by a plane (cutting_planes)
        }
    }
    on_ = true;
    make_rules();
    status_ = std::isnan(cost_)
                  ? fmt::format("on: {} planes", planes_.size())
                  : fmt::format("on: {} planes, estimated {:.3g} ms per row, budget {:.3g} ms ({:.0f}% of rows "
                                "complete)",
                                planes_.size(), cost_ * 1e-6,
                                (options.far_field_budget_ns + complete_ * options.far_field_row_ns) * 1e-6,
                                100 * complete_);
}

// Each patch joins the first plane (unoriented normal within 1e-9, every vertex within tol_)
// that holds it, or opens a new one.
bool FarField::group_planes() {
    const Scene& scene = patches_.scene;
    for (std::uint32_t i = 0; i < scene.size(); ++i) {
        const Patch& p = scene.patches[i];
        const Poly& poly = patches_.polys[i];
        Vec3 nc = p.normal;  // unoriented: the largest component positive
        const Vec3 a = glm::abs(nc);
        const int axis = a.x >= a.y && a.x >= a.z ? 0 : a.y >= a.z ? 1 : 2;
        if (nc[axis] < 0) nc = -nc;
        std::size_t found = planes_.size();
        for (std::size_t g = 0; g < planes_.size() && found == planes_.size(); ++g) {
            if (!(glm::dot(nc, planes_[g].n) > 1.0 - 1e-9)) continue;
            bool in = true;
            for (std::size_t k = 0; k < poly.n && in; ++k)
                in = std::abs(glm::dot(planes_[g].n, poly.v[k]) - planes_[g].d) <= tol_;
            if (in) found = g;
        }
        if (found == planes_.size()) {
            if (planes_.size() == kMaxPlanes) return false;
            planes_.push_back(Plane{nc, glm::dot(nc, p.centroid), 0, patches_.boxes[i], {}});
        }
        plane_of_.push_back(static_cast<std::uint32_t>(found));
        Plane& g = planes_[found];
        g.box.lo = glm::min(g.box.lo, patches_.boxes[i].lo);
        g.box.hi = glm::max(g.box.hi, patches_.boxes[i].hi);
        g.members.push_back(i);
        for (std::size_t k = 0; k < poly.n; ++k)
            g.thickness = std::max(g.thickness, std::abs(glm::dot(g.n, poly.v[k]) - g.d));
    }
    return true;
}

// Per patch and plane, two bits: a vertex strictly in front of the plane, one strictly behind.
void FarField::mark_sides() {
    const std::size_t n = patches_.size();
    words_ = (planes_.size() + 63) / 64;
    plus_bits_.assign(n * words_, 0);
    minus_bits_.assign(n * words_, 0);
    for (std::uint32_t i = 0; i < n; ++i)
        for (std::size_t g = 0; g < planes_.size(); ++g) {
            const Plane& P = planes_[g];
            // A plane whose members are not flat to tol_ (a warped quad) is a slab: a vertex
            // inside it counts as on both sides, so any pair near it is tested (and refused).
            const double lim = P.thickness > tol_ ? P.thickness + tol_ : tol_;
            const bool thick = P.thickness > tol_;
            for (std::size_t k = 0; k < patches_.polys[i].n; ++k) {
                const double s = glm::dot(P.n, patches_.polys[i].v[k]) - P.d;
                const bool above = s > lim || (thick && s >= -lim);
                const bool below = s < -lim || (thick && s <= lim);
                if (above) plus_bits_[i * words_ + g / 64] |= std::uint64_t{1} << (g % 64);
                if (below) minus_bits_[i * words_ + g / 64] |= std::uint64_t{1} << (g % 64);
            }
        }
}

void FarField::cutting_planes(std::uint32_t i, std::vector<std::uint32_t>& out) const {
    out.clear();
    if (planes_.empty()) return;
    const std::uint64_t* p = &plus_bits_[i * words_];
    const std::uint64_t* m = &minus_bits_[i * words_];
    for (std::size_t w = 0; w < words_; ++w) {
        std::uint64_t c = p[w] & m[w];
        while (c) {
            const auto g = static_cast<std::uint32_t>(w * 64 + static_cast<std::size_t>(std::countr_zero(c)));
            c &= c - 1;
            if (planes_[g].thickness <= tol_) out.push_back(g);  // a slab's bits say "near", not "cut"
        }
    }
}

void FarField::make_rules() {
    const std::size_t n = patches_.size();
    rules_.resize(n);
    std::vector<Vec3> pts;
    std::vector<double> wts;
    for (std::uint32_t i = 0; i < n; ++i)
        for (int r = 0; r < 2; ++r) {
            patch_quadrature(patches_.polys[i].span(), 2 + r, pts, wts);
            Rule& rule = rules_[i][static_cast<std::size_t>(r)];
            rule.n = static_cast<std::uint8_t>(pts.size());
            for (std::size_t k = 0; k < pts.size(); ++k) {
                rule.p[k] = pts[k];
                rule.w[k] = wts[k];
            }
        }
}

// Whether some patch of plane g other than i and j may meet the section of hull(i ∪ j) by that
// plane (conservatively: bounding boxes). The section of a convex hull by a plane is the convex
// hull of the hull's vertices in the plane and of the points where segments between vertices on
// opposite sides cross it.
bool FarField::section_meets(std::uint32_t i, std::uint32_t j, std::size_t g, const Box& pair) const {
    return section_meets(patches_.polys[i].span(), patches_.polys[j].span(), i, j, g, pair, false);
}

bool FarField::section_meets(std::span<const Vec3> pi, std::span<const Vec3> pj, std::uint32_t i, std::uint32_t j,
                             std::size_t g, const Box& pair, bool strict) const {
    const Plane& P = planes_[g];
    if (P.thickness > tol_) return true;
    // The section lies in the hull, so in the pair's bounding box: a plane whose members' box
    // misses that box blocks nothing (most conflicts in a room: a block's face plane cuts the
    // room, its face does not come near the pair).
    if (!pair.overlaps(P.box)) return false;
    std::array<Vec3, 10> v{};
    std::array<double, 10> s{};
    std::size_t m = 0;
    for (const Vec3& x : pi) v[m++] = x;
    for (const Vec3& x : pj) v[m++] = x;
    for (std::size_t k = 0; k < m; ++k) s[k] = glm::dot(P.n, v[k]) - P.d;
    Box sec{Vec3(INFINITY), Vec3(-INFINITY)};
    const auto add = [&](const Vec3& x) {
        sec.lo = glm::min(sec.lo, x);
        sec.hi = glm::max(sec.hi, x);
    };
    for (std::size_t a = 0; a < m; ++a) {
        if (std::abs(s[a]) <= tol_) add(v[a]);
        for (std::size_t b = 0; b < m; ++b)
            if (s[a] > tol_ && s[b] < -tol_) add(v[a] + (v[b] - v[a]) * (s[a] / (s[a] - s[b])));
    }
    if (strict) {
        // Members that only touch the section (within the tolerance, along an axis where both
        // boxes have extent) are let through: the inner corner of an L-shaped room, where the
        // wall beside the corner meets the receiver's edge, touches the section along that edge.
        const double t = 2 * tol_;
        const auto meets = [&](const Box& q) {
            for (int k = 0; k < 3; ++k) {
                const bool flat = sec.hi[k] - sec.lo[k] <= t || q.hi[k] - q.lo[k] <= t;
                if (flat ? (q.lo[k] > sec.hi[k] + t || sec.lo[k] > q.hi[k] + t)
                         : (q.lo[k] >= sec.hi[k] - t || sec.lo[k] >= q.hi[k] - t))
                    return false;
            }
            return true;
        };
        if (!meets(P.box)) return false;
        for (std::uint32_t q : P.members)
            if (q != i && q != j && meets(patches_.boxes[q])) return true;
        return false;
    }
    sec.lo -= Vec3(2 * tol_);
    sec.hi += Vec3(2 * tol_);
    if (!sec.overlaps(P.box)) return false;
    for (std::uint32_t q : P.members)
        if (q != i && q != j && patches_.boxes[q].overlaps(sec)) return true;
    return false;
}

// A segment from a point of i to a point of j meets a plane only where the two lie on opposite
// sides of it (or in it: touching, measure zero, as for the shaft test). So patches of a plane
// that no segment crosses block nothing, and where segments cross it, only members that meet the
// crossing region can.
bool FarField::unoccluded(std::uint32_t i, std::uint32_t j) const {
    if (planes_.empty()) return false;
    const std::uint64_t* pi = &plus_bits_[i * words_];
    const std::uint64_t* pj = &plus_bits_[j * words_];
    const std::uint64_t* mi = &minus_bits_[i * words_];
    const std::uint64_t* mj = &minus_bits_[j * words_];
    // The pair's bounding box, widened by the tolerance of touching.
    const Box box = patches_.pair_box(i, j);
    const Box pair{box.lo - Vec3(2 * tol_), box.hi + Vec3(2 * tol_)};
    // The flat planes of i and j themselves block nothing: a segment from i's front part ends on
    // j's plane (and starts on i's) without crossing it. Their bits are set only where the other
    // patch is cut by the plane (a sender cut by its receiver's plane: add_cut_sender_pairs),
    // and there only the part of it in front exchanges radiation.
    const auto own = [&](std::uint32_t p, std::size_t w) -> std::uint64_t {
        const std::uint32_t g = plane_of_[p];
        return g / 64 == w && planes_[g].thickness <= tol_ ? std::uint64_t{1} << (g % 64) : 0;
    };
    for (std::size_t w = 0; w < words_; ++w) {
        std::uint64_t c = (pi[w] | pj[w]) & (mi[w] | mj[w]) & ~(own(i, w) | own(j, w));
        while (c) {
            const std::size_t g = w * 64 + static_cast<std::size_t>(std::countr_zero(c));
            c &= c - 1;
            if (section_meets(i, j, g, pair)) return false;
        }
    }
    return true;
}

bool FarField::unoccluded_front(std::span<const Vec3> front, std::uint32_t i, std::uint32_t j) const {
    if (planes_.empty() || front.size() < 3 || front.size() > 5) return false;
    const Poly& pj = patches_.polys[j];
    Box box{Vec3(INFINITY), Vec3(-INFINITY)};
    for (const Vec3& x : front) {
        box.lo = glm::min(box.lo, x);
        box.hi = glm::max(box.hi, x);
    }
    box.lo = glm::min(box.lo, patches_.boxes[j].lo);
    box.hi = glm::max(box.hi, patches_.boxes[j].hi);
    const Box pair{box.lo - Vec3(2 * tol_), box.hi + Vec3(2 * tol_)};
    const std::uint64_t* pjb = &plus_bits_[j * words_];
    const std::uint64_t* mjb = &minus_bits_[j * words_];
    for (std::size_t g = 0; g < planes_.size(); ++g) {
        if (g == plane_of_[j] && planes_[g].thickness <= tol_) continue;  // ends on it: crosses nothing there
        const Plane& P = planes_[g];
        const double lim = P.thickness > tol_ ? P.thickness + tol_ : tol_;
        const bool thick = P.thickness > tol_;
        bool above = (pjb[g / 64] >> (g % 64)) & 1, below = (mjb[g / 64] >> (g % 64)) & 1;
        for (const Vec3& x : front) {
            const double d = glm::dot(P.n, x) - P.d;
            above = above || d > lim || (thick && d >= -lim);
            below = below || d < -lim || (thick && d <= lim);
        }
        if (above && below && section_meets(front, pj.span(), i, j, g, pair, true)) return false;
    }
    return true;
}

std::pair<double, double> FarField::value(std::uint32_t i, std::uint32_t j, double d) const {
    const Patch& pi = patches_.scene.patches[i];
    const Patch& pj = patches_.scene.patches[j];
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
        const Rule& a = rules_[i][fine];
        const Rule& b = rules_[j][fine];
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
    const auto poly = patches_.polys[j].span();
    const Rule& a = rules_[i][1];
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

}  // namespace ffcube::accuracy
