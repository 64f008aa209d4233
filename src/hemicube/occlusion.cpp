#include "ffcube/hemicube/occlusion.hpp"

#include <glm/geometric.hpp>
#include <glm/vec2.hpp>

#include <algorithm>
#include <array>
#include <cmath>

#include "ffcube/core/error.hpp"

namespace ffcube {

void FaceDepthRows::build(std::span<const float> depth, int atlas_width, const AtlasViewport& vp) {
    FFCUBE_CHECK_MSG(vp.x >= 0 && vp.y >= 0 && vp.width > 0 && vp.height > 0 && vp.x + vp.width <= atlas_width &&
                         static_cast<std::size_t>(vp.y + vp.height) * static_cast<std::size_t>(atlas_width) <= depth.size(),
                     "FaceDepthRows: the viewport lies outside the depth image");
    w_ = vp.width;
    h_ = vp.height;
    levels_ = std::bit_width(static_cast<unsigned>(w_));  // 2^(levels − 1) <= w
    plane_ = static_cast<std::size_t>(w_) * static_cast<std::size_t>(h_);
    min_.resize(plane_ * static_cast<std::size_t>(levels_));
    for (int y = 0; y < h_; ++y) {
        const float* row = depth.data() + static_cast<std::size_t>(vp.y + y) * static_cast<std::size_t>(atlas_width) + vp.x;
        std::copy(row, row + w_, min_.begin() + static_cast<std::ptrdiff_t>(static_cast<std::size_t>(y) * w_));
    }
    for (int k = 1; k < levels_; ++k) {
        const int half = 1 << (k - 1), n = w_ - (1 << k) + 1;  // runs of 2^k that fit
        for (int y = 0; y < h_; ++y) {
            const float* src = min_.data() + static_cast<std::size_t>(k - 1) * plane_ + static_cast<std::size_t>(y) * w_;
            float* dst = min_.data() + static_cast<std::size_t>(k) * plane_ + static_cast<std::size_t>(y) * w_;
            for (int x = 0; x < n; ++x) dst[x] = std::min(src[x], src[x + half]);
        }
    }
}

bool FaceDepthRows::covers(int x0, int y0, int x1, int y1, double d) const {
    if (w_ == 0) return false;
    x0 = std::max(x0, 0);
    y0 = std::max(y0, 0);
    x1 = std::min(x1, w_ - 1);
    y1 = std::min(y1, h_ - 1);
    if (x0 > x1 || y0 > y1) return true;
    for (int y = y0; y <= y1; ++y)
        if (!run_covers(y, x0, x1, d)) return false;
    return true;
}

bool FaceDepthRows::covers(const FaceFootprint& fp, double d) const {
    if (w_ == 0) return false;
    const int x0 = std::max(fp.x0, 0), x1 = std::min(fp.x1, w_ - 1);
    const int y0 = std::max(fp.y0, 0), y1 = std::min(fp.y1, h_ - 1);
    if (x0 > x1 || y0 > y1) return true;
    for (int y = y0; y <= y1; ++y) {
        // The centres X = x + 0.5 of this row with nx X <= c − ny Y for every half-plane.
        const double Y = y + 0.5;
        double lo = x0 + 0.5, hi = x1 + 0.5;
        for (int e = 0; e < fp.edges; ++e) {
            const auto& [nx, ny, c] = fp.edge[static_cast<std::size_t>(e)];
            const double r = c - ny * Y;
            if (nx > 0)
                hi = std::min(hi, r / nx);
            else if (nx < 0)
                lo = std::max(lo, r / nx);
            else if (r < 0)
                hi = -INFINITY;  // a horizontal line with this row outside
        }
        if (!(lo <= hi)) continue;  // no centre of this row
        const double xl = std::ceil(lo - 0.5), xh = std::floor(hi - 0.5);
        if (xl > xh) continue;
        if (!run_covers(y, static_cast<int>(xl), static_cast<int>(xh), d)) return false;
    }
    return true;
}

namespace {
// A unit axis vector, ±e_axis (axis −1: not one).
struct AxisPick {
    int axis = -1;
    double sign = 0;
    double of(const Vec3& v) const { return sign * v[axis]; }
};
AxisPick axis_pick(const Vec3& a) {
    for (int k = 0; k < 3; ++k)
        if ((a[k] == 1.0 || a[k] == -1.0) && a[(k + 1) % 3] == 0.0 && a[(k + 2) % 3] == 0.0) return {k, a[k]};
    return {};
}
}  // namespace

FaceFootprint face_footprint(const FaceSpec& f, std::span<const Vec3> corners, double near, bool edges) {
    const FaceFrustum& fr = f.frustum;
    const double w = f.viewport.width, h = f.viewport.height;
    // A polygon with more corners than the buffers hold (a piece with many T-vertices): the
    // whole face at depth 1, never culled.
    constexpr std::size_t kCap = 40;
    FaceFootprint fp;  // its arrays left unset (only their first `edges`, `verts` are read)
    if (corners.size() + 5 > kCap) {
        fp.x0 = fp.y0 = 0;
        fp.x1 = f.viewport.width - 1;
        fp.y1 = f.viewport.height - 1;
        fp.max_depth = 1.0;
        return fp;
    }
    const double sx = (fr.right - fr.left) / w, sy = (fr.top - fr.bottom) / h;
    // The frustum widened by one pixel: a = right·v, b = up·v, d = forward·v inside when
    // d >= near and left − sx <= a / d <= right + sx, bottom − sy <= b / d <= top + sy.
    const double L = fr.left - sx, R = fr.right + sx, B = fr.bottom - sy, T = fr.top + sy;
    using P = glm::dvec3;  // (a, b, d)
    const auto plane = [&](int i, const P& p) {
        switch (i) {
            case 0: return p.z - near;
            case 1: return p.x - L * p.z;
            case 2: return R * p.z - p.x;
            case 3: return p.y - B * p.z;
            default: return T * p.z - p.y;
        }
    };
    std::array<P, kCap> buf[2];
    P* poly = buf[0].data();
    std::size_t n = 0;
    bool inside = true;
    // The layout's faces look along the local frame's axes (HemicubeLayout): a component each,
    // signed, is the same value as the dot product (the other terms are exact zeros).
    const AxisPick ar = axis_pick(f.right), au = axis_pick(f.up), af = axis_pick(f.forward);
    const bool picks = ar.axis >= 0 && au.axis >= 0 && af.axis >= 0;
    for (const Vec3& v : corners) {
        const P p = picks ? P(ar.of(v), au.of(v), af.of(v)) : P(glm::dot(v, f.right), glm::dot(v, f.up), glm::dot(v, f.forward));
        inside = inside && p.z >= near && p.x >= L * p.z && p.x <= R * p.z && p.y >= B * p.z && p.y <= T * p.z;
        poly[n++] = p;
    }
    // Sutherland–Hodgman against each plane in turn (only when a corner lies outside one: the
    // clipped polygon of one wholly inside is itself). The polygon is convex and planar (pieces
    // are: scene/mesher.cpp), so the result is exactly its part inside every plane; each plane
    // adds at most one vertex.
    for (int i = 0; i < 5 && !inside && n > 0; ++i) {
        P* next = poly == buf[0].data() ? buf[1].data() : buf[0].data();
        std::size_t m = 0;
        for (std::size_t k = 0; k < n; ++k) {
            const P& a = poly[k];
            const P& b = poly[k + 1 == n ? 0 : k + 1];
            const double ga = plane(i, a), gb = plane(i, b);
            if (ga >= 0) next[m++] = a;
            if ((ga >= 0) != (gb >= 0)) next[m++] = a + (ga / (ga - gb)) * (b - a);
        }
        poly = next;
        n = m;
    }
    fp.x0 = fp.y0 = 0;
    fp.x1 = fp.y1 = -1;
    fp.max_depth = 0.0;
    if (n == 0) return fp;  // no point of it can make a fragment on this face
    double dmin = INFINITY, cx0 = INFINITY, cx1 = -INFINITY, cy0 = INFINITY, cy1 = -INFINITY, mx = 0, my = 0;
    const bool keep = n <= static_cast<std::size_t>(FaceFootprint::kMaxVerts);
    const double kx = w / (fr.right - fr.left), ky = h / (fr.top - fr.bottom);
    for (std::size_t k = 0; k < n; ++k) {
        const P& p = poly[k];
        // d >= near up to the rounding of an intersection point on the near plane: the
        // projection is bounded (by the widened frustum, up to that rounding).
        const double d = std::max(p.z, near);
        dmin = std::min(dmin, d);
        const double col = (p.x / d - fr.left) * kx;
        const double row = (p.y / d - fr.bottom) * ky;
        cx0 = std::min(cx0, col);
        cx1 = std::max(cx1, col);
        cy0 = std::min(cy0, row);
        cy1 = std::max(cy1, row);
        mx += col;
        my += row;
        if (keep) fp.vert[k] = {col, row};
    }
    // Grown by one pixel, then clamped (as doubles first, against any rounding far outside).
    const auto lo = [](double c, double size) { return static_cast<int>(std::clamp(std::floor(c) - 1, -1.0, size)); };
    const auto hi = [](double c, double size) { return static_cast<int>(std::clamp(std::floor(c) + 1, -1.0, size)); };
    fp.x0 = std::max(0, lo(cx0, w));
    fp.y0 = std::max(0, lo(cy0, h));
    fp.x1 = std::min(f.viewport.width - 1, hi(cx1, w));
    fp.y1 = std::min(f.viewport.height - 1, hi(cy1, h));
    fp.max_depth = near / dmin;
    if (fp.x0 > fp.x1 || fp.y0 > fp.y1) return fp;
    // The probe: the pixel under the projected vertices' mean, a point of the polygon's image
    // (its centre within 0.71 pixel of it, so inside every half-plane below), if it lies on the
    // face; the query looks at it first.
    const double pxd = std::floor(mx / static_cast<double>(n)), pyd = std::floor(my / static_cast<double>(n));
    if (pxd >= fp.x0 && pxd <= fp.x1 && pyd >= fp.y0 && pyd <= fp.y1) {
        fp.probe_x = static_cast<int>(pxd);
        fp.probe_y = static_cast<int>(pyd);
    }
    fp.verts = keep ? static_cast<int>(n) : 0;
    if (edges) add_half_planes(fp);
    return fp;
}

bool add_half_planes(FaceFootprint& fp) {
    const int n = fp.verts;
    if (fp.edges > 0) return true;
    if (n < 3 || (fp.x1 - fp.x0 < 4 && fp.y1 - fp.y0 < 4)) return false;
    for (int k = 0; k < n && fp.edges < FaceFootprint::kMaxEdges; ++k) {
        const auto& a = fp.vert[static_cast<std::size_t>(k)];
        const auto& b = fp.vert[static_cast<std::size_t>(k + 1 == n ? 0 : k + 1)];
        const double ex = b[0] - a[0], ey = b[1] - a[1];
        const double len2 = ex * ex + ey * ey;
        if (!(len2 > 1e-6)) continue;  // a degenerate edge (a clipped corner): no direction
        const double inv = 1.0 / std::sqrt(len2);
        const double nx = ey * inv, ny = -ex * inv;
        double plus = -INFINITY, minus = -INFINITY;
        for (int j = 0; j < n; ++j) {
            const auto& v = fp.vert[static_cast<std::size_t>(j)];
            const double t = nx * (v[0] - a[0]) + ny * (v[1] - a[1]);
            plus = std::max(plus, t);
            minus = std::max(minus, -t);
        }
        const double sgn = plus <= minus ? 1.0 : -1.0;
        fp.edge[static_cast<std::size_t>(fp.edges++)] = {sgn * nx, sgn * ny, sgn * (nx * a[0] + ny * a[1]) + std::min(plus, minus) + 1.0};
    }
    return fp.edges > 0;
}

bool hidden_behind(const FaceDepthRows& depth, FaceFootprint& fp) {
    if (fp.x0 > fp.x1 || fp.y0 > fp.y1) return true;  // it fills no pixel of this face
    const double d = fp.max_depth / (1.0 - kOcclusionMargin);
    if (fp.probe_x >= 0 && !depth.covers(fp.probe_x, fp.probe_y, fp.probe_x, fp.probe_y, d)) return false;
    if (depth.covers(fp.x0, fp.y0, fp.x1, fp.y1, d)) return true;
    return add_half_planes(fp) && depth.covers(fp, d);
}

namespace {
// Nodes of at most this many pieces are not tested: their pieces' own tests cost about as much
// as the node's (measured on a 5,000-facet city: 8 to 32 alike; with 4 or 64 the run took as
// long as without the walk).
constexpr std::size_t kMinItems = 16;
}  // namespace

std::size_t hide_hidden_nodes(const PieceBvh& bvh, const std::array<FaceSpec, 5>& faces,
                              const std::array<FaceDepthRows, 5>& depth, const Vec3& eye, const HemicubeFrame& frame,
                              double near, unsigned open, HiddenFaces& out) {
    out.begin(bvh.size());
    std::size_t hidden = 0;
    // The layout's faces look along the local axes: a signed component is the dot product.
    std::array<std::array<AxisPick, 3>, 5> pick;
    std::array<bool, 5> picks{};
    for (std::size_t f = 0; f < 5; ++f) {
        pick[f] = {axis_pick(faces[f].right), axis_pick(faces[f].up), axis_pick(faces[f].forward)};
        picks[f] = pick[f][0].axis >= 0 && pick[f][1].axis >= 0 && pick[f][2].axis >= 0;
    }
    bvh.walk(open, [&](const BvhBox& box, unsigned bits, std::span<const std::uint32_t> items) -> unsigned {
        if (items.size() <= kMinItems) return 0;
        // The box's corners in the local frame: the centre's and the half extents' images.
        const Vec3 c = (box.lo + box.hi) * 0.5 - eye, h = (box.hi - box.lo) * 0.5;
        const Vec3 lc(glm::dot(c, frame.tangent), glm::dot(c, frame.bitangent), glm::dot(c, frame.normal));
        const Vec3 hx = h.x * Vec3(frame.tangent.x, frame.bitangent.x, frame.normal.x);
        const Vec3 hy = h.y * Vec3(frame.tangent.y, frame.bitangent.y, frame.normal.y);
        const Vec3 hz = h.z * Vec3(frame.tangent.z, frame.bitangent.z, frame.normal.z);
        std::array<Vec3, 8> corner;
        double mag = 0;
        for (int k = 0; k < 8; ++k) {
            corner[static_cast<std::size_t>(k)] = lc + (k & 1 ? hx : -hx) + (k & 2 ? hy : -hy) + (k & 4 ? hz : -hz);
            const Vec3& v = corner[static_cast<std::size_t>(k)];
            mag = std::max(mag, std::abs(v.x) + std::abs(v.y) + std::abs(v.z));
        }
        // Every piece corner's float lies within E of the box (in each local coordinate): its
        // rounding to float is at most 2^-24 ≈ 6e-8 of the coordinate, the double arithmetic of
        // both (subtracting the eye, three dot products) about 1e-15 of the corner's distance.
        const double E = 2e-7 * mag;
        unsigned left = bits;
        for (std::size_t f = 0; f < 5; ++f) {
            if (!(bits & (1u << f))) continue;
            const FaceSpec& fs = faces[f];
            const FaceFrustum& fr = fs.frustum;
            // The corners in the face's frame, and which of its frustum's planes each lies beyond.
            std::array<double, 8> ca, cb, cd;
            unsigned outside = 0x1f;
            double dlo = INFINITY;
            for (std::size_t k = 0; k < 8; ++k) {
                if (picks[f]) {
                    ca[k] = pick[f][0].of(corner[k]);
                    cb[k] = pick[f][1].of(corner[k]);
                    cd[k] = pick[f][2].of(corner[k]);
                } else {
                    ca[k] = glm::dot(corner[k], fs.right);
                    cb[k] = glm::dot(corner[k], fs.up);
                    cd[k] = glm::dot(corner[k], fs.forward);
                }
                dlo = std::min(dlo, cd[k]);
                outside &= (cd[k] < near ? 1u : 0u) | (ca[k] < fr.left * cd[k] ? 2u : 0u) |
                           (ca[k] > fr.right * cd[k] ? 4u : 0u) | (cb[k] < fr.bottom * cd[k] ? 8u : 0u) |
                           (cb[k] > fr.top * cd[k] ? 16u : 0u);
            }
            // Wholly beyond one plane: nothing under it shows on this face (its pieces are culled
            // from it, or at the edge tested alone). Leaving a face out of the walk never marks.
            if (outside != 0) {
                left &= ~(1u << f);
                continue;
            }
            // Reaching nearer than the near plane, or behind the eye: undecided here (the
            // projection is unbounded, or the depth bound is 1, which nothing can be behind).
            if (!(dlo - E >= near)) continue;
            double ma = 0, mb = 0, a0 = INFINITY, a1 = -INFINITY, b0 = INFINITY, b1 = -INFINITY;
            for (std::size_t k = 0; k < 8; ++k) {
                const double a = ca[k] / cd[k], b = cb[k] / cd[k];
                a0 = std::min(a0, a);
                a1 = std::max(a1, a);
                b0 = std::min(b0, b);
                b1 = std::max(b1, b);
                ma = std::max(ma, std::abs(a));
                mb = std::max(mb, std::abs(b));
            }
            // A point within E of the box: |a'/d' − a/d| <= E (1 + |a/d|) / (d − E).
            const double da = E * (1 + ma) / (dlo - E), db = E * (1 + mb) / (dlo - E);
            const double w = fs.viewport.width, hgt = fs.viewport.height;
            const double kx = w / (fr.right - fr.left), ky = hgt / (fr.top - fr.bottom);
            // The piece footprint's rectangle from these (face_footprint's growth and clamping,
            // which are monotone: a piece's rectangle lies inside).
            const auto lo = [](double v, double size) { return static_cast<int>(std::clamp(std::floor(v) - 1, -1.0, size)); };
            const auto hi = [](double v, double size) { return static_cast<int>(std::clamp(std::floor(v) + 1, -1.0, size)); };
            const int x0 = std::max(0, lo((a0 - da - fr.left) * kx, w));
            const int x1 = std::min(fs.viewport.width - 1, hi((a1 + da - fr.left) * kx, w));
            const int y0 = std::max(0, lo((b0 - db - fr.bottom) * ky, hgt));
            const int y1 = std::min(fs.viewport.height - 1, hi((b1 + db - fr.bottom) * ky, hgt));
            // Wholly off the face: its pieces are culled from it (or, at the edge, tested alone).
            if (x0 > x1 || y0 > y1) {
                left &= ~(1u << f);
                continue;
            }
            const double d = near / (dlo - E) / (1.0 - kOcclusionMargin);
            if (!depth[f].covers(x0, y0, x1, y1, d)) continue;
            for (const std::uint32_t g : items) out.add(g, 1u << f);
            left &= ~(1u << f);
            ++hidden;
        }
        return left;
    });
    return hidden;
}

}  // namespace ffcube
