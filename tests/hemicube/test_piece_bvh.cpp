// PieceBvh (hemicube/piece_bvh.hpp) against brute force: every box with a corner in front of
// the plane is marked (soundness: the worker would draw it), and every box marked has its
// highest corner within the stated margin of the plane (tightness: it prunes what it says).
#include <gtest/gtest.h>

#include <glm/common.hpp>
#include <glm/geometric.hpp>

#include <algorithm>
#include <cstdint>
#include <random>
#include <vector>

#include "ffcube/hemicube/piece_bvh.hpp"

namespace ffcube {
namespace {

// max over the 8 corners of dot(corner − o, n): the box's highest point, by brute force.
double highest_corner(const BvhBox& b, const Vec3& o, const Vec3& n) {
    double best = -INFINITY;
    for (int k = 0; k < 8; ++k) {
        const Vec3 c((k & 1) ? b.hi.x : b.lo.x, (k & 2) ? b.hi.y : b.lo.y, (k & 4) ? b.hi.z : b.lo.z);
        best = std::max(best, glm::dot(c - o, n));
    }
    return best;
}

std::vector<BvhBox> random_boxes(std::mt19937_64& rng, std::size_t n, const Vec3& offset) {
    std::uniform_real_distribution<double> pos(-100, 100), ext(0, 1);
    std::vector<BvhBox> boxes;
    for (std::size_t i = 0; i < n; ++i) {
        const Vec3 c = offset + Vec3(pos(rng), pos(rng), pos(rng));
        // Sizes from 1e-3 to 10, some flat in one axis (a wall or a floor).
        const double s = std::pow(10.0, 4 * ext(rng) - 3);
        Vec3 h(s * ext(rng), s * ext(rng), s * ext(rng));
        if (i % 3 == 0) h[static_cast<int>(i / 3 % 3)] = 0;
        boxes.push_back({c - h, c + h});
    }
    return boxes;
}

void check_against_brute_force(const std::vector<BvhBox>& boxes, const Vec3& offset, std::mt19937_64& rng) {
    const PieceBvh bvh(boxes);
    ASSERT_EQ(bvh.size(), boxes.size());
    BvhBox all = boxes[0];
    for (const BvhBox& b : boxes) all = {glm::min(all.lo, b.lo), glm::max(all.hi, b.hi)};
    std::uniform_real_distribution<double> pos(-120, 120), dir(-1, 1);
    std::vector<std::uint32_t> visit(boxes.size(), 0);
    for (std::uint32_t q = 1; q <= 200; ++q) {
        // Planes through the scene, some through a box's corner exactly (a box touching the plane
        // from behind has its highest point at height 0: in front, by the definition).
        Vec3 o = offset + Vec3(pos(rng), pos(rng), pos(rng));
        if (q % 4 == 0) o = boxes[q % boxes.size()].hi;
        Vec3 n(dir(rng), dir(rng), dir(rng));
        if (q % 5 == 0) n = Vec3(0, 0, dir(rng) < 0 ? -1 : 1);  // axis-aligned: many boxes flat on it
        if (glm::dot(n, n) < 1e-6) continue;
        const std::size_t marked = bvh.mark_in_front(o, n, visit, q);
        // The margin as documented: 1e-9 × (scene size + distance to its centre) × |n|.
        const double margin = 1e-9 * (glm::length(all.hi - all.lo) + glm::length(o - (all.lo + all.hi) * 0.5)) *
                              glm::length(n);
        std::size_t count = 0;
        for (std::size_t b = 0; b < boxes.size(); ++b) {
            const double h = highest_corner(boxes[b], o, n);
            const bool is_marked = visit[b] == q;
            count += is_marked;
            if (h >= 0) {
                EXPECT_TRUE(is_marked) << "box " << b << " has a corner " << h << " in front, query " << q;
            }
            // The bound the tree uses is the same maximum, computed from centre and half extents:
            // it differs from the corners' by rounding (1e-16 relative), far below the margin.
            if (is_marked) {
                EXPECT_GE(h, -2 * margin) << "box " << b << " lies " << -h << " behind, query " << q;
            }
            if (h < -2 * margin) { EXPECT_FALSE(is_marked); }
        }
        EXPECT_EQ(marked, count);
    }
}

TEST(PieceBvh, MarksExactlyTheBoxesInFrontOfRandomPlanes) {
    std::mt19937_64 rng(15);
    for (const std::size_t n : {1u, 3u, 4u, 5u, 17u, 1000u}) {
        const std::vector<BvhBox> boxes = random_boxes(rng, n, Vec3(0));
        check_against_brute_force(boxes, Vec3(0), rng);
    }
}

TEST(PieceBvh, MarksExactlyTheBoxesInFrontFarFromTheOrigin) {
    // A GIS export: coordinates about 5e6 (UTM northings), boxes of 1e-3 to 10 among them.
    std::mt19937_64 rng(16);
    const Vec3 offset(5e5, 5.4e6, 300);
    check_against_brute_force(random_boxes(rng, 2000, offset), offset, rng);
}

TEST(PieceBvh, PrunesWholeSubtreesBehindThePlane) {
    // 1,000 boxes [i, i + 0.5] along x: the plane x = 500.75 facing +x has 501..999 in front.
    std::vector<BvhBox> boxes;
    for (int i = 0; i < 1000; ++i) boxes.push_back({Vec3(i, 0, 0), Vec3(i + 0.5, 1, 1)});
    const PieceBvh bvh(boxes);
    std::vector<std::uint32_t> visit(boxes.size(), 0);
    EXPECT_EQ(bvh.mark_in_front(Vec3(500.75, 0, 0), Vec3(1, 0, 0), visit, 1), 499u);
    for (int i = 0; i < 1000; ++i) EXPECT_EQ(visit[static_cast<std::size_t>(i)] == 1, i >= 501) << i;
    // Touching: box 500 ends at x = 500.5, on the plane.
    EXPECT_EQ(bvh.mark_in_front(Vec3(500.5, 0, 0), Vec3(1, 0, 0), visit, 2), 500u);
    EXPECT_EQ(visit[500], 2u);
    EXPECT_NE(visit[499], 2u);  // its highest point, 499.5, is 1 behind
}

TEST(PieceBvh, PieceBoxesAreTheCornersBoxes) {
    PatchGrid t;
    t.corners = {Vec3(0, 0, 0), Vec3(2, -1, 0), Vec3(1, 3, 5), Vec3(1, 3, 5)};
    t.count = 3;
    PatchGrid q;
    q.corners = {Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(1, 1, 0), Vec3(-7, 1, 0)};
    const std::vector<PatchGrid> gs{t, q};
    const std::vector<BvhBox> b = PieceBvh::piece_boxes(gs);
    ASSERT_EQ(b.size(), 2u);
    EXPECT_EQ(b[0].lo, Vec3(0, -1, 0));
    EXPECT_EQ(b[0].hi, Vec3(2, 3, 5));
    EXPECT_EQ(b[1].lo, Vec3(-7, 0, 0));
    EXPECT_EQ(b[1].hi, Vec3(1, 1, 0));
}

TEST(PieceBvh, EmptySceneMarksNothing) {
    const PieceBvh bvh(std::vector<BvhBox>{});
    std::vector<std::uint32_t> visit;
    EXPECT_EQ(bvh.mark_in_front(Vec3(0), Vec3(0, 0, 1), visit, 1), 0u);
}

}  // namespace
}  // namespace ffcube
