// PointGrid: corner positions bucketed for find_edge_vertices (src/hemicube/pieces.cpp).
#pragma once

#include <glm/common.hpp>
#include <glm/geometric.hpp>

#include <algorithm>
#include <array>
#include <bit>
#include <cmath>
#include <cstdint>
#include <unordered_map>
#include <utility>
#include <vector>

#include "ffcube/geometry/polygon.hpp"

namespace ffcube {

// Points bucketed in a hierarchy of uniform grids: level 0 has cells of size h, level L cells of
// 2^L × 2^L × 2^L level-0 cells. near_segment() walks a segment at the level where it takes a
// step or two and goes down a level only where a step's box holds a point, so a segment costs
// about its length in level-0 cells where points lie near it, and a few steps per level through
// empty space, however long it is. Keys are hashes of cell coordinates: cells that share a key
// merely have their points tested in vain.
class PointGrid {
public:
    PointGrid(const std::vector<Vec3>& points, double h) : h_(h) {
        origin_ = points.empty() ? Vec3(0.0) : points.front();
        for (const Vec3& p : points) origin_ = glm::min(origin_, p);
        std::int64_t top = 1;
        std::vector<std::array<std::int64_t, 3>> cells(points.size());
        for (std::size_t i = 0; i < points.size(); ++i) {
            cells[i] = {cell(points[i].x, origin_.x), cell(points[i].y, origin_.y), cell(points[i].z, origin_.z)};
            top = std::max({top, cells[i][0], cells[i][1], cells[i][2]});
        }
        levels_ = std::min(static_cast<int>(std::bit_width(static_cast<std::uint64_t>(top))) + 1, 62);
        count_ = static_cast<std::uint32_t>(points.size());
        by_cell_.resize(points.size());
        for (std::size_t i = 0; i < points.size(); ++i)
            by_cell_[i] = {key(cells[i], 0), static_cast<std::uint32_t>(i)};
        std::sort(by_cell_.begin(), by_cell_.end());
        ranges_.reserve(by_cell_.size());
        for (std::uint32_t i = 0; i < by_cell_.size();) {
            std::uint32_t j = i;
            while (j < by_cell_.size() && by_cell_[j].first == by_cell_[i].first) ++j;
            ranges_.emplace(by_cell_[i].first, std::pair{i, j});
            i = j;
        }
        // The occupied cells of each level, from those of the level below (fewer and fewer).
        occupied_.resize(static_cast<std::size_t>(levels_));
        std::sort(cells.begin(), cells.end());
        cells.erase(std::unique(cells.begin(), cells.end()), cells.end());
        for (int l = 1; l < levels_; ++l) {
            for (auto& c : cells)
                for (auto& v : c) v >>= 1;
            std::sort(cells.begin(), cells.end());
            cells.erase(std::unique(cells.begin(), cells.end()), cells.end());
            auto& occ = occupied_[static_cast<std::size_t>(l)];
            for (const auto& c : cells) occ.push_back(key(c, 0));  // c is already level l's
            std::sort(occ.begin(), occ.end());
        }
    }

    // Calls f(index) for every point within the box of the segment a → b widened by tol (and
    // for some others, some of them more than once). A tolerance wider than a cell (an edge a
    // billion times the cell, or coordinates some 1e15 times it) is met by testing every point.
    template <typename F>
    void near_segment(const Vec3& a, const Vec3& b, double tol, F&& f) const {
        if (!(tol <= h_)) {
            for (std::uint32_t i = 0; i < count_; ++i) f(i);
            return;
        }
        const double len = glm::length(b - a);
        int level = 0;
        while (level + 1 < levels_ && std::ldexp(h_, level) < len) ++level;
        visit(level, a, b, 0.0, 1.0, tol, f);
    }

private:
    std::int64_t cell(double x, double o) const { return static_cast<std::int64_t>(std::floor((x - o) / h_)); }
    static std::uint64_t key(const std::array<std::int64_t, 3>& c, int level) {
        std::uint64_t k = static_cast<std::uint64_t>(c[0] >> level) * 0x9E3779B97F4A7C15ull;
        k ^= static_cast<std::uint64_t>(c[1] >> level) * 0xC2B2AE3D27D4EB4Full + (k << 6) + (k >> 2);
        k ^= static_cast<std::uint64_t>(c[2] >> level) * 0x165667B19E3779F9ull + (k << 6) + (k >> 2);
        return k;
    }
    // The part s0..s1 of a → b, at this level: in steps of at most one cell, each step's box
    // widened by tol.
    template <typename F>
    void visit(int level, const Vec3& a, const Vec3& b, double s0, double s1, double tol, F& f) const {
        const Vec3 d = b - a;
        const double cell_size = std::ldexp(h_, level);
        const auto steps = static_cast<std::size_t>(std::max(1.0, std::ceil((s1 - s0) * glm::length(d) / cell_size)));
        for (std::size_t i = 0; i < steps; ++i) {
            const double t0 = s0 + (s1 - s0) * static_cast<double>(i) / static_cast<double>(steps);
            const double t1 = i + 1 == steps ? s1 : s0 + (s1 - s0) * static_cast<double>(i + 1) / static_cast<double>(steps);
            const Vec3 p0 = a + d * t0, p1 = a + d * t1;
            const Vec3 lo = glm::min(p0, p1) - tol, hi = glm::max(p0, p1) + tol;
            const std::array<std::int64_t, 3> c0 = {cell(lo.x, origin_.x), cell(lo.y, origin_.y), cell(lo.z, origin_.z)};
            const std::array<std::int64_t, 3> c1 = {cell(hi.x, origin_.x), cell(hi.y, origin_.y), cell(hi.z, origin_.z)};
            bool any = false;
            for (std::int64_t x = c0[0] >> level; x <= c1[0] >> level && !any; ++x)
                for (std::int64_t y = c0[1] >> level; y <= c1[1] >> level && !any; ++y)
                    for (std::int64_t z = c0[2] >> level; z <= c1[2] >> level && !any; ++z) {
                        const std::uint64_t k = key({x, y, z}, 0);  // already shifted
                        if (level > 0) {
                            const auto& occ = occupied_[static_cast<std::size_t>(level)];
                            any = std::binary_search(occ.begin(), occ.end(), k);
                            continue;
                        }
                        const auto it = ranges_.find(k);
                        if (it == ranges_.end()) continue;
                        for (std::uint32_t j = it->second.first; j < it->second.second; ++j) f(by_cell_[j].second);
                    }
            if (any) visit(level - 1, a, b, t0, t1, tol, f);
        }
    }

    double h_;
    Vec3 origin_{0.0};
    int levels_ = 1;
    std::uint32_t count_ = 0;
    std::vector<std::pair<std::uint64_t, std::uint32_t>> by_cell_;  // level 0: (key, point), sorted
    std::unordered_map<std::uint64_t, std::pair<std::uint32_t, std::uint32_t>> ranges_;  // key → by_cell_ run
    std::vector<std::vector<std::uint64_t>> occupied_;             // levels ≥ 1: sorted keys
};

}  // namespace ffcube
