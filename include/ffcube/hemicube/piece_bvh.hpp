// A bounding volume hierarchy over boxes (the hemicube's pieces), for the one query a hemicube
// makes of the whole scene: which pieces may lie in front of its plane. A hemicube of a roof
// patch has most of a city behind it; with the hierarchy it touches only the pieces that can be
// in front (and the nodes on the way), not every piece of the scene (issue 15, part 3).
#pragma once

#include <cstdint>
#include <span>
#include <utility>
#include <vector>

#include "ffcube/scene/scene.hpp"

namespace ffcube {

struct BvhBox {
    Vec3 lo{0.0}, hi{0.0};
};

class PieceBvh {
public:
    PieceBvh() = default;
    // Built once per scene: median splits along the longest axis of the box centres, at most
    // kLeafSize boxes a leaf. O(n log² n). Boxes must be finite.
    explicit PieceBvh(std::span<const BvhBox> boxes);

    // The boxes of a scene's pieces (their corners).
    static std::vector<BvhBox> piece_boxes(std::span<const PatchGrid> grids);

    // Sets visit[b] = stamp for every box b that may have a point p with dot(p − origin, normal)
    // ≥ 0, and returns how many: every box whose highest point over the plane, max over the box
    // of dot(p − origin, normal), is at least −margin, where margin = 1e-9 × (the scene's size
    // + the distance from origin to it). The margin makes the answer sound under rounding: a box
    // left out has every point at least margin behind the plane, far more than the rounding of
    // dot(p − origin, normal) computed in double at any of its points (about 1e-16 of the same
    // scale), so such a point's computed height is < 0. normal need not be of unit length
    // (margin scales with it). visit must have one entry per box.
    std::size_t mark_in_front(const Vec3& origin, const Vec3& normal, std::vector<std::uint32_t>& visit,
                              std::uint32_t stamp) const;

    // Depth first from the root, for a query that settles whole subtrees at once (occlusion
    // culling by nodes: hemicube/occlusion.hpp): at each node visited,
    // open = decide(box, open, items) gets the node's box, the query's bits still open above it
    // and the indices of the boxes under it (a contiguous range), and returns the bits left open
    // below it. The walk goes below a node while bits stay open and it is not a leaf.
    template <class Decide>
    void walk(unsigned open, Decide&& decide) const {
        if (nodes_.empty() || open == 0) return;
        std::pair<std::uint32_t, unsigned> stack[64];  // depth ≤ log2(n / kLeafSize) + 1 (median splits)
        int top = 0;
        stack[top++] = {0u, open};
        while (top > 0) {
            const auto [at, bits] = stack[--top];
            const Node& nd = nodes_[at];
            const unsigned left =
                decide(nd.box, bits, std::span<const std::uint32_t>(items_.data() + nd.begin, nd.end - nd.begin));
            if (left == 0 || nd.count > 0) continue;
            stack[top++] = {nd.first, left};
            stack[top++] = {at + 1, left};
        }
    }

    std::size_t size() const { return items_.size(); }
    std::size_t node_count() const { return nodes_.size(); }

    static constexpr std::uint32_t kLeafSize = 4;

private:
    struct Node {
        BvhBox box;
        std::uint32_t first = 0;  // leaf: first of items_; inner: index of the second child
        std::uint32_t count = 0;  // leaf: number of items (> 0); inner: 0 (first child follows)
        std::uint32_t begin = 0, end = 0;  // the items under it: items_[begin, end)
    };
    std::uint32_t build(std::span<const BvhBox> boxes, std::vector<Vec3>& centres, std::uint32_t begin,
                        std::uint32_t end);

    std::vector<Node> nodes_;
    std::vector<std::uint32_t> items_;
    std::vector<BvhBox> item_boxes_;  // in items_ order
    double scene_size_ = 0;
    Vec3 scene_centre_{0.0};
};

}  // namespace ffcube
