#include "ffcube/hemicube/occlusion.hpp"

#include <glm/geometric.hpp>
#include <glm/vec2.hpp>

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

bool FaceDepthPyramid::cell_covers_fp(int k, int cx, int cy, const FaceFootprint& fp, double d) const {
    if (static_cast<double>(min_[offset_[k] + static_cast<std::size_t>(cy) * w_[k] + cx]) > d) return true;
    const int px0 = cx << k, px1 = std::min(((cx + 1) << k) - 1, w_[0] - 1);
    const int py0 = cy << k, py1 = std::min(((cy + 1) << k) - 1, h_[0] - 1);
    // The pixel centres of the cell's part of the rectangle: [X0, X1] × [Y0, Y1].
    const double X0 = std::max(px0, fp.x0) + 0.5, X1 = std::min(px1, fp.x1) + 0.5;
    const double Y0 = std::max(py0, fp.y0) + 0.5, Y1 = std::min(py1, fp.y1) + 0.5;
    bool inside = true;  // every such centre satisfies every half-plane
    for (int e = 0; e < fp.edges; ++e) {
        const auto& [nx, ny, c] = fp.edge[static_cast<std::size_t>(e)];
        const double lo = nx * (nx > 0 ? X0 : X1) + ny * (ny > 0 ? Y0 : Y1);
        if (lo > c) return true;  // no centre of the polygon's pixels here
        inside = inside && nx * (nx > 0 ? X1 : X0) + ny * (ny > 0 ? Y1 : Y0) <= c;
    }
    if (k == 0) return false;  // a pixel of the footprint not nearer than d
    // Wholly inside: the pixel that sets its minimum is one of the footprint's.
    if (inside && px0 >= fp.x0 && px1 <= fp.x1 && py0 >= fp.y0 && py1 <= fp.y1) return false;
    const int c = k - 1;
    const int ccx0 = std::max(2 * cx, fp.x0 >> c), ccx1 = std::min({2 * cx + 1, w_[c] - 1, fp.x1 >> c});
    const int ccy0 = std::max(2 * cy, fp.y0 >> c), ccy1 = std::min({2 * cy + 1, h_[c] - 1, fp.y1 >> c});
    for (int yy = ccy0; yy <= ccy1; ++yy)
        for (int xx = ccx0; xx <= ccx1; ++xx)
            if (!cell_covers_fp(c, xx, yy, fp, d)) return false;
    return true;
}

bool FaceDepthPyramid::covers(const FaceFootprint& fp_in, double d) const {
    if (w_.empty()) return false;
    FaceFootprint fp = fp_in;
    fp.x0 = std::max(fp.x0, 0);
    fp.y0 = std::max(fp.y0, 0);
    fp.x1 = std::min(fp.x1, w_[0] - 1);
    fp.y1 = std::min(fp.y1, h_[0] - 1);
    if (fp.x0 > fp.x1 || fp.y0 > fp.y1) return true;
    // The probe first: a pixel of the footprint, often one that shows the polygon or the sky.
    if (fp.probe_x >= fp.x0 && fp.probe_x <= fp.x1 && fp.probe_y >= fp.y0 && fp.probe_y <= fp.y1 &&
        !(static_cast<double>(min_[static_cast<std::size_t>(fp.probe_y) * w_[0] + fp.probe_x]) > d))
        return false;
    int k = 0;
    while ((fp.x1 >> k) - (fp.x0 >> k) > 1 || (fp.y1 >> k) - (fp.y0 >> k) > 1) ++k;
    for (int cy = fp.y0 >> k; cy <= fp.y1 >> k; ++cy)
        for (int cx = fp.x0 >> k; cx <= fp.x1 >> k; ++cx)
            if (!cell_covers_fp(k, cx, cy, fp, d)) return false;
    return true;
}

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
    for (const Vec3& v : corners) {
        const P p(glm::dot(v, f.right), glm::dot(v, f.up), glm::dot(v, f.forward));
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
    std::array<glm::dvec2, kCap> proj;
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
        proj[k] = glm::dvec2(col, row);
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
    if (n <= static_cast<std::size_t>(FaceFootprint::kMaxVerts)) {
        fp.verts = static_cast<int>(n);
        for (std::size_t k = 0; k < n; ++k) fp.vert[k] = {proj[k].x, proj[k].y};
    }
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

bool hidden_behind(const FaceDepthPyramid& depth, FaceFootprint& fp) {
    if (fp.x0 > fp.x1 || fp.y0 > fp.y1) return true;  // it fills no pixel of this face
    const double d = fp.max_depth / (1.0 - kOcclusionMargin);
    if (fp.probe_x >= 0 && !depth.covers(fp.probe_x, fp.probe_y, fp.probe_x, fp.probe_y, d)) return false;
    if (depth.covers(fp.x0, fp.y0, fp.x1, fp.y1, d)) return true;
    return add_half_planes(fp) && depth.covers(fp, d);
}

}  // namespace ffcube
