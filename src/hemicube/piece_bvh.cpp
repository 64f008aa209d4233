#include "ffcube/hemicube/piece_bvh.hpp"

#include <glm/common.hpp>
#include <glm/geometric.hpp>

#include <algorithm>
#include <cmath>

#include "ffcube/core/error.hpp"

namespace ffcube {

namespace {

BvhBox join(const BvhBox& a, const BvhBox& b) { return {glm::min(a.lo, b.lo), glm::max(a.hi, b.hi)}; }

// The highest point of the box over the plane through origin with normal n: the centre's
// height plus the half extents weighted by |n|.
double box_height(const BvhBox& b, const Vec3& origin, const Vec3& n) {
    const Vec3 c = (b.lo + b.hi) * 0.5, h = (b.hi - b.lo) * 0.5;
    return glm::dot(c - origin, n) + glm::dot(h, glm::abs(n));
}

}  // namespace

std::vector<BvhBox> PieceBvh::piece_boxes(std::span<const PatchGrid> grids) {
    std::vector<BvhBox> boxes;
    boxes.reserve(grids.size());
    for (const PatchGrid& g : grids) {
        BvhBox b{g.corners[0], g.corners[0]};
        for (std::uint32_t k = 1; k < g.count; ++k) b = join(b, BvhBox{g.corners[k], g.corners[k]});
        boxes.push_back(b);
    }
    return boxes;
}

PieceBvh::PieceBvh(std::span<const BvhBox> boxes) {
    const auto n = static_cast<std::uint32_t>(boxes.size());
    items_.resize(n);
    std::vector<Vec3> centres(n);
    for (std::uint32_t i = 0; i < n; ++i) {
        items_[i] = i;
        centres[i] = (boxes[i].lo + boxes[i].hi) * 0.5;
        FFCUBE_CHECK_MSG(std::isfinite(glm::dot(centres[i], centres[i])), "piece box is not finite");
    }
    if (n == 0) return;
    nodes_.reserve(2 * (n / kLeafSize + 1));
    build(boxes, centres, 0, n);
    item_boxes_.resize(n);
    for (std::uint32_t i = 0; i < n; ++i) item_boxes_[i] = boxes[items_[i]];
    const BvhBox& root = nodes_[0].box;
    scene_centre_ = (root.lo + root.hi) * 0.5;
    scene_size_ = glm::length(root.hi - root.lo);
}

std::uint32_t PieceBvh::build(std::span<const BvhBox> boxes, std::vector<Vec3>& centres, std::uint32_t begin,
                              std::uint32_t end) {
    const auto at = static_cast<std::uint32_t>(nodes_.size());
    nodes_.emplace_back();
    BvhBox box = boxes[items_[begin]];
    BvhBox cbox{centres[items_[begin]], centres[items_[begin]]};
    for (std::uint32_t i = begin + 1; i < end; ++i) {
        box = join(box, boxes[items_[i]]);
        cbox = join(cbox, BvhBox{centres[items_[i]], centres[items_[i]]});
    }
    nodes_[at].box = box;
    nodes_[at].begin = begin;
    nodes_[at].end = end;
    if (end - begin <= kLeafSize) {
        nodes_[at].first = begin;
        nodes_[at].count = end - begin;
        return at;
    }
    const Vec3 ext = cbox.hi - cbox.lo;
    const int axis = ext.x >= ext.y && ext.x >= ext.z ? 0 : ext.y >= ext.z ? 1 : 2;
    const std::uint32_t mid = begin + (end - begin) / 2;
    // Ties broken by index: the tree, and so the order of nothing visible, depends only on the input.
    std::nth_element(items_.begin() + begin, items_.begin() + mid, items_.begin() + end,
                     [&](std::uint32_t a, std::uint32_t b) {
                         return centres[a][axis] < centres[b][axis] || (centres[a][axis] == centres[b][axis] && a < b);
                     });
    build(boxes, centres, begin, mid);
    const std::uint32_t second = build(boxes, centres, mid, end);
    nodes_[at].first = second;
    nodes_[at].count = 0;
    return at;
}

std::size_t PieceBvh::mark_in_front(const Vec3& origin, const Vec3& normal, std::vector<std::uint32_t>& visit,
                                    std::uint32_t stamp) const {
    FFCUBE_CHECK_MSG(visit.size() == items_.size(), "PieceBvh::mark_in_front: one visit entry per box");
    if (nodes_.empty()) return 0;
    const double margin = 1e-9 * (scene_size_ + glm::length(origin - scene_centre_)) * glm::length(normal);
    std::size_t marked = 0;
    std::uint32_t stack[64];
    int top = 0;
    stack[top++] = 0;
    while (top > 0) {
        const Node& nd = nodes_[stack[--top]];
        if (box_height(nd.box, origin, normal) < -margin) continue;
        if (nd.count > 0) {
            for (std::uint32_t k = nd.first; k < nd.first + nd.count; ++k)
                if (box_height(item_boxes_[k], origin, normal) >= -margin) {
                    visit[items_[k]] = stamp;
                    ++marked;
                }
        } else {
            // Depth ≤ log2(n / kLeafSize) + 1 < 64 for any 32-bit count (median splits).
            const auto self = static_cast<std::uint32_t>(&nd - nodes_.data());
            stack[top++] = nd.first;
            stack[top++] = self + 1;
        }
    }
    return marked;
}

}  // namespace ffcube
