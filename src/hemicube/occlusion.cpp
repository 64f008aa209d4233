#include "ffcube/hemicube/occlusion.hpp"

#include <glm/geometric.hpp>

#include <algorithm>
#include <cmath>

#include "ffcube/core/error.hpp"

namespace ffcube {

void FaceDepthTiles::build(std::span<const float> depth, int atlas_width, const AtlasViewport& vp) {
    FFCUBE_CHECK_MSG(vp.x >= 0 && vp.y >= 0 && vp.width > 0 && vp.height > 0 && vp.x + vp.width <= atlas_width &&
                         static_cast<std::size_t>(vp.y + vp.height) * static_cast<std::size_t>(atlas_width) <= depth.size(),
                     "FaceDepthTiles: the viewport lies outside the depth image");
    tiles_x_ = (vp.width + kTile - 1) / kTile;
    tiles_y_ = (vp.height + kTile - 1) / kTile;
    min_.assign(static_cast<std::size_t>(tiles_x_) * static_cast<std::size_t>(tiles_y_), INFINITY);
    for (int y = 0; y < vp.height; ++y) {
        const float* row = depth.data() + static_cast<std::size_t>(vp.y + y) * static_cast<std::size_t>(atlas_width) + vp.x;
        float* tile_row = min_.data() + static_cast<std::size_t>(y / kTile) * static_cast<std::size_t>(tiles_x_);
        for (int tx = 0; tx < tiles_x_; ++tx) {
            const int end = std::min(vp.width, (tx + 1) * kTile);
            float m = tile_row[tx];
            for (int x = tx * kTile; x < end; ++x) m = std::min(m, row[x]);
            tile_row[tx] = m;
        }
    }
}

bool FaceDepthTiles::covers(int x0, int y0, int x1, int y1, double d) const {
    if (x0 > x1 || y0 > y1) return true;
    const int tx0 = std::max(0, x0 / kTile), tx1 = std::min(tiles_x_ - 1, x1 / kTile);
    const int ty0 = std::max(0, y0 / kTile), ty1 = std::min(tiles_y_ - 1, y1 / kTile);
    for (int ty = ty0; ty <= ty1; ++ty) {
        const float* row = min_.data() + static_cast<std::size_t>(ty) * static_cast<std::size_t>(tiles_x_);
        for (int tx = tx0; tx <= tx1; ++tx)
            if (!(static_cast<double>(row[tx]) > d)) return false;
    }
    return true;
}

std::optional<FaceFootprint> face_footprint(const FaceSpec& f, std::span<const Vec3> corners, double near) {
    if (corners.empty()) return std::nullopt;
    const FaceFrustum& fr = f.frustum;
    const double w = f.viewport.width, h = f.viewport.height;
    double dmin = INFINITY, cx0 = INFINITY, cx1 = -INFINITY, cy0 = INFINITY, cy1 = -INFINITY;
    for (const Vec3& v : corners) {
        const double d = glm::dot(v, f.forward);
        // A corner on or behind the face's eye plane (or all but on it): the projection is
        // unbounded or ill-conditioned; this polygon is never culled on this face.
        if (!(d > 1e-6 * glm::length(v))) return std::nullopt;
        dmin = std::min(dmin, d);
        const double col = (glm::dot(v, f.right) / d - fr.left) / (fr.right - fr.left) * w;
        const double row = (glm::dot(v, f.up) / d - fr.bottom) / (fr.top - fr.bottom) * h;
        cx0 = std::min(cx0, col);
        cx1 = std::max(cx1, col);
        cy0 = std::min(cy0, row);
        cy1 = std::max(cy1, row);
    }
    // Grown by one pixel, then clamped (as doubles first: a corner just in front of the eye
    // plane projects far beyond int's range).
    const auto lo = [](double c, double size) { return static_cast<int>(std::clamp(std::floor(c) - 1, -1.0, size)); };
    const auto hi = [](double c, double size) { return static_cast<int>(std::clamp(std::floor(c) + 1, -1.0, size)); };
    FaceFootprint fp{};
    fp.x0 = std::max(0, lo(cx0, w));
    fp.y0 = std::max(0, lo(cy0, h));
    fp.x1 = std::min(f.viewport.width - 1, hi(cx1, w));
    fp.y1 = std::min(f.viewport.height - 1, hi(cy1, h));
    fp.max_depth = near / dmin;
    return fp;
}

}  // namespace ffcube
