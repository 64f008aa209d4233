// The uniform grid of patch bounding boxes (see spatial_grid.hpp).
#include "accuracy/spatial_grid.hpp"

#include <algorithm>
#include <cmath>

namespace ffcube::accuracy {

std::array<long, 3> SpatialGrid::cell_of(const Vec3& p) const {
    const Vec3 c = (p - origin_) / h_;
    return {static_cast<long>(std::floor(c.x)), static_cast<long>(std::floor(c.y)), static_cast<long>(std::floor(c.z))};
}

std::uint64_t SpatialGrid::key(long x, long y, long z) {
    // 21 bits per axis; the grid spans at most 2^21 cells per axis (h ≥ extent / 2^20).
    const auto u = [](long v) { return static_cast<std::uint64_t>(v) & 0x1FFFFFu; };
    return u(x) | (u(y) << 21) | (u(z) << 42);
}

SpatialGrid::SpatialGrid(const PatchSet& patches) : boxes_(patches.boxes) {
    const Scene& s = patches.scene;
    const std::size_t n = patches.size();
    if (n == 0) return;
    // Cell side: the median patch size (most patches then fall in a few cells), but no finer
    // than 2^-20 of the extent so that cell coordinates fit the hash key.
    std::vector<double> sizes = patches.sizes;
    std::nth_element(sizes.begin(), sizes.begin() + static_cast<long>(n / 2), sizes.end());
    h_ = std::max({sizes[n / 2], s.extent() * std::ldexp(1.0, -20), 1e-300});
    origin_ = s.bbox_min - Vec3(h_);
    for (std::uint32_t i = 0; i < n; ++i) {
        const auto a = cell_of(boxes_[i].lo), b = cell_of(boxes_[i].hi);
        const long count = (b[0] - a[0] + 1) * (b[1] - a[1] + 1) * (b[2] - a[2] + 1);
        if (count > kMaxCellsPerQuery) {
            // A patch far larger than the median would fill thousands of cells: it goes on a
            // list that every query scans instead.
            big_.push_back(i);
            continue;
        }
        for (long x = a[0]; x <= b[0]; ++x)
            for (long y = a[1]; y <= b[1]; ++y)
                for (long z = a[2]; z <= b[2]; ++z) cells_[key(x, y, z)].push_back(i);
    }
}

// The patches of the cells `box` touches whose boxes meet it (sorted, unique); every patch when
// the box spans too many cells.
void SpatialGrid::query_cells(const Box& box, std::vector<std::uint32_t>& out) const {
    out.clear();
    const auto a = cell_of(box.lo), b = cell_of(box.hi);
    const long count = (b[0] - a[0] + 1) * (b[1] - a[1] + 1) * (b[2] - a[2] + 1);
    if (count > kMaxCellsPerQuery) {
        for (std::uint32_t q = 0; q < boxes_.size(); ++q)
            if (boxes_[q].overlaps(box)) out.push_back(q);
        return;
    }
    for (long x = a[0]; x <= b[0]; ++x)
        for (long y = a[1]; y <= b[1]; ++y)
            for (long z = a[2]; z <= b[2]; ++z) {
                const auto it = cells_.find(key(x, y, z));
                if (it == cells_.end()) continue;
                for (std::uint32_t q : it->second)
                    if (boxes_[q].overlaps(box)) out.push_back(q);
            }
    std::sort(out.begin(), out.end());
    out.erase(std::unique(out.begin(), out.end()), out.end());
}

void SpatialGrid::query(const Box& box, std::vector<std::uint32_t>& out) const {
    query_cells(box, out);
    bool added = false;
    for (std::uint32_t q : big_)
        if (boxes_[q].overlaps(box)) {
            out.push_back(q);
            added = true;
        }
    if (added) {
        std::sort(out.begin(), out.end());
        out.erase(std::unique(out.begin(), out.end()), out.end());
    }
}

}  // namespace ffcube::accuracy
