// Internal to the accuracy layer. One job: find the patches whose bounding boxes may meet a
// query box (near-pair search and shaft-test candidates), in O(cells touched) per query.
#pragma once

#include <array>
#include <cstdint>
#include <unordered_map>
#include <vector>

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

    double cell_size() const { return h_; }
    std::size_t big_patches() const { return big_.size(); }

    static constexpr long kMaxCellsPerQuery = 4096;  // beyond: scan every patch instead

private:
    std::array<long, 3> cell_of(const Vec3& p) const;
    static std::uint64_t key(long x, long y, long z);
    void query_cells(const Box& box, std::vector<std::uint32_t>& out) const;

    const std::vector<Box>& boxes_;
    Vec3 origin_{0.0};
    double h_ = 1;
    std::unordered_map<std::uint64_t, std::vector<std::uint32_t>> cells_;
    std::vector<std::uint32_t> big_;  // patches too large for the grid, checked by every query
};

}  // namespace ffcube::accuracy
