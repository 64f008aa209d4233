// Internal to the accuracy layer. One job: find the patches whose bounding boxes may meet a
// query box (near-pair search and shaft-test candidates), in O(cells touched) per query.
#pragma once

#include <algorithm>
#include <array>
#include <cstdint>
#include <unordered_map>
#include <vector>

#include <glm/common.hpp>

#include "accuracy/patch_set.hpp"

namespace ffcube::accuracy {

// Uniform grid of the patches' bounding boxes, built once per scene (O(patches)); cell side the
// median patch size. Const after construction: queries are thread-safe.
class SpatialGrid {
public:
    explicit SpatialGrid(const PatchSet& patches);

    // Every patch whose bounding box meets `box`, including the patches too large for the grid:
    // sorted, unique, exactly those (the cells only narrow the search; the boxes decide).
    void query(const Box& box, std::vector<std::uint32_t>& out) const;

    // Calls visit(q) once for every patch whose bounding box meets `box`, in no set order, until
    // it returns false; returns whether every call returned true. For tests whose answer does
    // not depend on the order (the shaft test): no list is made or sorted, and the first
    // blocker ends the search. A patch in several cells is visited in one only: the cell of
    // max(box.lo, its box's lo), which the query and the patch both cover.
    template <class Visit>
    bool visit(const Box& box, Visit&& visit) const;

    double cell_size() const { return h_; }
    std::size_t big_patches() const { return big_.size(); }

    static constexpr long kMaxCellsPerQuery = 4096;  // beyond: scan every patch instead

private:
    std::array<long, 3> cell_of(const Vec3& p) const;
    static std::uint64_t key(long x, long y, long z);
    void query_cells(const Box& box, std::vector<std::uint32_t>& out) const;
    bool is_big(std::uint32_t q) const { return std::binary_search(big_.begin(), big_.end(), q); }

    const std::vector<Box>& boxes_;
    Vec3 origin_{0.0};
    double h_ = 1;
    std::unordered_map<std::uint64_t, std::vector<std::uint32_t>> cells_;
    std::vector<std::uint32_t> big_;  // patches too large for the grid, checked by every query
};

template <class Visit>
bool SpatialGrid::visit(const Box& box, Visit&& visit) const {
    for (std::uint32_t q : big_)
        if (boxes_[q].overlaps(box) && !visit(q)) return false;
    const auto a = cell_of(box.lo), b = cell_of(box.hi);
    const long count = (b[0] - a[0] + 1) * (b[1] - a[1] + 1) * (b[2] - a[2] + 1);
    if (count > kMaxCellsPerQuery) {
        for (std::uint32_t q = 0; q < boxes_.size(); ++q)
            if (!is_big(q) && boxes_[q].overlaps(box) && !visit(q)) return false;
        return true;
    }
    for (long x = a[0]; x <= b[0]; ++x)
        for (long y = a[1]; y <= b[1]; ++y)
            for (long z = a[2]; z <= b[2]; ++z) {
                const auto it = cells_.find(key(x, y, z));
                if (it == cells_.end()) continue;
                for (std::uint32_t q : it->second) {
                    const Box& qb = boxes_[q];
                    if (!qb.overlaps(box)) continue;
                    if (cell_of(glm::max(qb.lo, box.lo)) != std::array<long, 3>{x, y, z}) continue;  // visited elsewhere
                    if (!visit(q)) return false;
                }
            }
    return true;
}

}  // namespace ffcube::accuracy
