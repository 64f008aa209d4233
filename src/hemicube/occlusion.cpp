#include "ffcube/hemicube/occlusion.hpp"

#include <glm/geometric.hpp>

#include <algorithm>
#include <array>
#include <cmath>

#include "ffcube/core/error.hpp"

namespace ffcube {

void FaceDepthPyramid::build(std::span<const float> depth, int atlas_width, const AtlasViewport& vp) {
    FFCUBE_CHECK_MSG(vp.x >= 0 && vp.y >= 0 && vp.width > 0 && vp.height > 0 && vp.x + vp.width <= atlas_width &&
                         static_cast<std::size_t>(vp.y + vp.height) * static_cast<std::size_t>(atlas_width) <= depth.size(),
                     "FaceDepthPyramid: the viewport lies outside the depth image");
    w_.assign(1, vp.width);
    h_.assign(1, vp.height);
    offset_.assign(1, 0);
    std::size_t total = static_cast<std::size_t>(vp.width) * static_cast<std::size_t>(vp.height);
    while (w_.back() > 1 || h_.back() > 1) {
        offset_.push_back(total);
        w_.push_back((w_.back() + 1) / 2);
        h_.push_back((h_.back() + 1) / 2);
        total += static_cast<std::size_t>(w_.back()) * static_cast<std::size_t>(h_.back());
    }
    min_.resize(total);
    for (int y = 0; y < vp.height; ++y) {
        const float* row = depth.data() + static_cast<std::size_t>(vp.y + y) * static_cast<std::size_t>(atlas_width) + vp.x;
        std::copy(row, row + vp.width, min_.begin() + static_cast<std::ptrdiff_t>(static_cast<std::size_t>(y) * vp.width));
    }
    for (std::size_t k = 1; k < w_.size(); ++k) {
        const int cw = w_[k - 1], ch = h_[k - 1];
        const float* child = min_.data() + offset_[k - 1];
        float* cell = min_.data() + offset_[k];
        for (int y = 0; y < h_[k]; ++y) {
            const float* r0 = child + static_cast<std::size_t>(2 * y) * cw;
            const float* r1 = 2 * y + 1 < ch ? r0 + cw : r0;  // an odd top row: its cells have one child row
            for (int x = 0; x < w_[k]; ++x) {
                const int x1 = 2 * x + 1 < cw ? 2 * x + 1 : 2 * x;
                cell[static_cast<std::size_t>(y) * w_[k] + x] = std::min(std::min(r0[2 * x], r0[x1]), std::min(r1[2 * x], r1[x1]));
            }
        }
    }
}

bool FaceDepthPyramid::cell_covers(int k, int cx, int cy, int x0, int y0, int x1, int y1, double d) const {
    if (static_cast<double>(min_[offset_[k] + static_cast<std::size_t>(cy) * w_[k] + cx]) > d) return true;
    if (k == 0) return false;  // a pixel of the rectangle not nearer than d
    const int px0 = cx << k, px1 = std::min(((cx + 1) << k) - 1, w_[0] - 1);
    const int py0 = cy << k, py1 = std::min(((cy + 1) << k) - 1, h_[0] - 1);
    // Wholly inside: the pixel that sets its minimum is one of the rectangle's.
    if (px0 >= x0 && px1 <= x1 && py0 >= y0 && py1 <= y1) return false;
    const int c = k - 1;
    const int ccx0 = std::max(2 * cx, x0 >> c), ccx1 = std::min({2 * cx + 1, w_[c] - 1, x1 >> c});
    const int ccy0 = std::max(2 * cy, y0 >> c), ccy1 = std::min({2 * cy + 1, h_[c] - 1, y1 >> c});
    for (int yy = ccy0; yy <= ccy1; ++yy)
        for (int xx = ccx0; xx <= ccx1; ++xx)
            if (!cell_covers(c, xx, yy, x0, y0, x1, y1, d)) return false;
    return true;
}

bool FaceDepthPyramid::covers(int x0, int y0, int x1, int y1, double d) const {
    if (w_.empty()) return false;
    x0 = std::max(x0, 0);
    y0 = std::max(y0, 0);
    x1 = std::min(x1, w_[0] - 1);
    y1 = std::min(y1, h_[0] - 1);
    if (x0 > x1 || y0 > y1) return true;
    // The finest level at which the rectangle meets at most 2 × 2 cells.
    int k = 0;
    while ((x1 >> k) - (x0 >> k) > 1 || (y1 >> k) - (y0 >> k) > 1) ++k;
    for (int cy = y0 >> k; cy <= y1 >> k; ++cy)
        for (int cx = x0 >> k; cx <= x1 >> k; ++cx)
            if (!cell_covers(k, cx, cy, x0, y0, x1, y1, d)) return false;
    return true;
}

FaceFootprint face_footprint(const FaceSpec& f, std::span<const Vec3> corners, double near) {
    const FaceFrustum& fr = f.frustum;
    const double w = f.viewport.width, h = f.viewport.height;
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
    thread_local std::vector<P> poly, next;
    poly.clear();
    bool inside = true;
    for (const Vec3& v : corners) {
        const P p(glm::dot(v, f.right), glm::dot(v, f.up), glm::dot(v, f.forward));
        for (int i = 0; i < 5 && inside; ++i) inside = plane(i, p) >= 0;
        poly.push_back(p);
    }
    // Sutherland–Hodgman against each plane in turn (only when a corner lies outside one: the
    // clipped polygon of one wholly inside is itself). The polygon is convex and planar (pieces
    // are: scene/mesher.cpp), so the result is exactly its part inside every plane.
    for (int i = 0; i < 5 && !inside && !poly.empty(); ++i) {
        next.clear();
        for (std::size_t k = 0; k < poly.size(); ++k) {
            const P& a = poly[k];
            const P& b = poly[(k + 1) % poly.size()];
            const double ga = plane(i, a), gb = plane(i, b);
            if (ga >= 0) next.push_back(a);
            if ((ga >= 0) != (gb >= 0)) next.push_back(a + (ga / (ga - gb)) * (b - a));
        }
        poly.swap(next);
    }
    FaceFootprint fp{0, 0, -1, -1, 0.0};
    if (poly.empty()) return fp;  // no point of it can make a fragment on this face
    double dmin = INFINITY, cx0 = INFINITY, cx1 = -INFINITY, cy0 = INFINITY, cy1 = -INFINITY;
    for (const P& p : poly) {
        // d >= near up to the rounding of an intersection point on the near plane: the
        // projection is bounded (by the widened frustum, up to that rounding).
        const double d = std::max(p.z, near);
        dmin = std::min(dmin, d);
        const double col = (p.x / d - fr.left) / (fr.right - fr.left) * w;
        const double row = (p.y / d - fr.bottom) / (fr.top - fr.bottom) * h;
        cx0 = std::min(cx0, col);
        cx1 = std::max(cx1, col);
        cy0 = std::min(cy0, row);
        cy1 = std::max(cy1, row);
    }
    // Grown by one pixel, then clamped (as doubles first, against any rounding far outside).
    const auto lo = [](double c, double size) { return static_cast<int>(std::clamp(std::floor(c) - 1, -1.0, size)); };
    const auto hi = [](double c, double size) { return static_cast<int>(std::clamp(std::floor(c) + 1, -1.0, size)); };
    fp.x0 = std::max(0, lo(cx0, w));
    fp.y0 = std::max(0, lo(cy0, h));
    fp.x1 = std::min(f.viewport.width - 1, hi(cx1, w));
    fp.y1 = std::min(f.viewport.height - 1, hi(cy1, h));
    fp.max_depth = near / dmin;
    return fp;
}

}  // namespace ffcube
