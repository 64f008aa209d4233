// The hemicube's pieces on the CPU (hemicube/pieces.hpp): twins, T-vertices found on the right
// edges (also far from the origin), and triangulations that cover each piece exactly.
#include <gtest/gtest.h>

#include <glm/geometric.hpp>

#include <cmath>
#include <cstdint>
#include <limits>
#include <set>
#include <vector>

#include "ffcube/hemicube/pieces.hpp"

namespace ffcube {
namespace {

PatchGrid quad(Vec3 a, Vec3 b, Vec3 c, Vec3 d) {
    PatchGrid g;
    g.corners = {a, b, c, d};
    g.count = 4;
    return g;
}
PatchGrid tri(Vec3 a, Vec3 b, Vec3 c) {
    PatchGrid g;
    g.corners = {a, b, c, c};
    g.count = 3;
    return g;
}
std::vector<PatchGrid> numbered(std::vector<PatchGrid> gs) {
    for (std::uint32_t k = 0; k < gs.size(); ++k) gs[k].first_patch = k;
    return gs;
}

// Twice the signed area of triangle (a, b, c) along n.
double signed_area(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& n) {
    return 0.5 * glm::dot(glm::cross(b - a, c - a), n);
}

// The piece's area as a fan from corner 0: differences of nearby coordinates are exact, so
// this keeps full precision far from the origin too.
double polygon_area_of(const PatchGrid& g) {
    const Vec3 n = polygon_normal(std::span<const Vec3>(g.corners.data(), g.count));
    double a = 0;
    for (std::uint32_t k = 1; k + 1 < g.count; ++k) a += signed_area(g.corners[0], g.corners[k], g.corners[k + 1], n);
    return a;
}

// Checks piece g's triangles: as many as its boundary has vertices less two, each with positive
// area along the piece's normal (CCW from the front), only the piece's own vertex slots, every
// slot used, and areas summing to the piece's area, up to 'moved': the area by which a T-vertex
// off the edge (within edge_tolerance) moves the outline.
void expect_covers_exactly(const ScenePieces& sp, const PatchGrid& pg, std::uint32_t g, std::size_t t_vertices,
                           double moved = 0) {
    const std::uint32_t first = sp.first[g], last = sp.first[g + 1];
    ASSERT_EQ(last - first, pg.count + t_vertices) << "piece " << g;
    const std::uint32_t t0 = sp.tri_first[g], t1 = sp.tri_first[g + 1];
    if (t_vertices == 0) {
        EXPECT_EQ(t0, t1) << "a piece without T-vertices keeps its corner triangles";
        return;
    }
    ASSERT_EQ((t1 - t0) / 3, pg.count + t_vertices - 2) << "piece " << g;
    const Vec3 n = polygon_normal(std::span<const Vec3>(pg.corners.data(), pg.count));
    double sum = 0;
    std::set<std::uint32_t> used;
    for (std::uint32_t t = t0; t < t1; t += 3) {
        for (std::uint32_t k = 0; k < 3; ++k) {
            EXPECT_GE(sp.tris[t + k], first);
            EXPECT_LT(sp.tris[t + k], last);
            used.insert(sp.tris[t + k]);
        }
        const double a = signed_area(sp.pos[sp.tris[t]], sp.pos[sp.tris[t + 1]], sp.pos[sp.tris[t + 2]], n);
        EXPECT_GT(a, 1e-12 * polygon_area_of(pg)) << "triangle " << (t - t0) / 3 << " of piece " << g;
        sum += a;
    }
    EXPECT_EQ(used.size(), last - first) << "every boundary vertex is a triangle corner";
    EXPECT_NEAR(sum, polygon_area_of(pg), 1e-12 * polygon_area_of(pg) + moved) << "piece " << g;
}

TEST(Pieces, TwinsAreSameCornersFacingAway) {
    const Vec3 a(0, 0, 0), b(1, 0, 0), c(1, 1, 0), d(0, 1, 0);
    const auto gs = numbered({quad(a, b, c, d),                                     // up
                              quad(a, d, c, b),                                     // down: its twin
                              quad(b, c, d, a),                                     // up again, rotated
                              quad(a + Vec3(0, 0, 1), b + Vec3(0, 0, 1), c + Vec3(0, 0, 1), d + Vec3(0, 0, 1))});
    const auto twin = find_twins(gs);
    ASSERT_EQ(twin.size(), 4u);
    EXPECT_EQ(twin[0], 1);
    EXPECT_EQ(twin[1], 1);
    EXPECT_EQ(twin[2], 1) << "same corner set in another order, facing away from piece 1";
    EXPECT_EQ(twin[3], 0) << "a plate elsewhere";
    // Only pieces facing the same way: no twins.
    EXPECT_EQ(find_twins(numbered({quad(a, b, c, d), quad(b, c, d, a)})), (std::vector<std::uint8_t>{0, 0}));
    // A triangle over the same corners as part of a quad is no twin.
    EXPECT_EQ(find_twins(numbered({quad(a, b, c, d), tri(a, c, b)})), (std::vector<std::uint8_t>{0, 0}));
}

// A long floor piece beside two short ones: their shared corner (1,1) lies inside the long
// one's edge 2 and nowhere else.
std::vector<PatchGrid> long_and_two_short(const Vec3& o, double s) {
    const auto p = [&](double x, double y) { return o + Vec3(x, y, 0) * s; };
    return numbered({quad(p(0, 0), p(2, 0), p(2, 1), p(0, 1)),
                     quad(p(0, 1), p(1, 1), p(1, 2), p(0, 2)),
                     quad(p(1, 1), p(2, 1), p(2, 2), p(1, 2))});
}

TEST(Pieces, TVertexGoesOnTheEdgeItLiesIn) {
    const auto gs = long_and_two_short(Vec3(0.0), 1.0);
    std::vector<Vec3> corners;
    const auto tv = find_edge_vertices(gs, corners);
    ASSERT_EQ(tv.size(), 1u);
    // Piece 0's edge 2 (corner 2 → 3: (2,1) → (0,1)) holds (1,1) half way.
    EXPECT_EQ(tv[0].g, 0u);
    EXPECT_EQ(tv[0].k, 2u);
    EXPECT_DOUBLE_EQ(tv[0].t, 0.5);
    EXPECT_EQ(corners[tv[0].at], Vec3(1, 1, 0));
    EXPECT_EQ(corners.size(), 8u) << "unique corner positions";

    const ScenePieces sp = prepare_pieces(gs);
    expect_covers_exactly(sp, gs[0], 0, 1);
    expect_covers_exactly(sp, gs[1], 1, 0);
    expect_covers_exactly(sp, gs[2], 2, 0);
    // The T-vertex slot (after piece 0's corners) is the other pieces' corner, bit for bit.
    EXPECT_EQ(sp.pos[sp.first[0] + 4], Vec3(1, 1, 0));
    EXPECT_EQ(sp.pos[sp.first[1] + 1], sp.pos[sp.first[0] + 4]);
}

// Corners that touch an edge only at its end, or lie on its line beyond it, or off it by more
// than the tolerance, are not T-vertices.
TEST(Pieces, NoTVertexAtEndpointsBeyondOrOffTheEdge) {
    const auto gs = numbered({quad({0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}),
                              quad({1, 0, 0}, {2, 0, 0}, {2, 1, 0}, {1, 1, 0}),             // shares an edge
                              quad({3, 1, 0}, {4, 1, 0}, {4, 2, 0}, {3, 2, 0}),             // on edge lines, beyond
                              quad({0.5, 1 + 1e-5, 0}, {0.7, 1 + 1e-5, 0}, {0.7, 2, 0}, {0.5, 2, 0})});  // 1e-5 off
    std::vector<Vec3> corners;
    EXPECT_TRUE(find_edge_vertices(gs, corners).empty());
}

// Several T-vertices on several edges of one piece: the triangulation covers the piece, no
// triangle lies along one edge, and the area adds up.
TEST(Pieces, TriangulationOfManyTVerticesCoversThePiece) {
    // Square 0..4; edge 0 (y = 0) holds x = 1, 2, 3 (three pieces below), edge 2 (y = 4) x = 1.
    std::vector<PatchGrid> gs = {quad({0, 0, 0}, {4, 0, 0}, {4, 4, 0}, {0, 4, 0})};
    for (int k = 0; k < 4; ++k)
        gs.push_back(quad({k, -1, 0}, {k + 1, -1, 0}, {k + 1, 0, 0}, {k, 0, 0}));
    gs.push_back(quad({0, 4, 0}, {1, 4, 0}, {1, 5, 0}, {0, 5, 0}));
    gs.push_back(quad({1, 4, 0}, {4, 4, 0}, {4, 5, 0}, {1, 5, 0}));
    gs = numbered(gs);
    std::vector<Vec3> corners;
    const auto tv = find_edge_vertices(gs, corners);
    std::vector<std::pair<std::uint32_t, double>> on_piece0;
    for (const EdgeVertex& e : tv) {
        EXPECT_EQ(e.g, 0u) << "only the big square has corners inside its edges";
        on_piece0.emplace_back(e.k, e.t);
    }
    EXPECT_EQ(on_piece0, (std::vector<std::pair<std::uint32_t, double>>{{0, 0.25}, {0, 0.5}, {0, 0.75}, {2, 0.75}}));
    const ScenePieces sp = prepare_pieces(gs);
    expect_covers_exactly(sp, gs[0], 0, 4);
    // No triangle with all three vertices on y = 0 or on y = 4.
    for (std::uint32_t t = sp.tri_first[0]; t < sp.tri_first[1]; t += 3)
        for (double y : {0.0, 4.0}) {
            int on = 0;
            for (std::uint32_t k = 0; k < 3; ++k) on += sp.pos[sp.tris[t + k]].y == y;
            EXPECT_LT(on, 3) << "triangle " << (t - sp.tri_first[0]) / 3 << " lies along y = " << y;
        }
}

TEST(Pieces, TriangulateBoundaryDirectly) {
    // A triangle (corners 0, 2, 4) with T-vertices 1 (edge 0) and 3 (edge 1).
    const std::vector<Vec3> pos = {{0, 0, 0}, {1, 0, 0}, {2, 0, 0}, {1, 1, 0}, {0, 2, 0}};
    const std::vector<std::uint32_t> b = {0, 1, 2, 3, 4};
    const std::vector<std::uint8_t> on = {0b101, 0b001, 0b011, 0b010, 0b110};
    std::vector<std::uint32_t> tris;
    triangulate_boundary(b, on, pos, tris);
    ASSERT_EQ(tris.size(), 9u);
    double sum = 0;
    for (std::size_t t = 0; t < tris.size(); t += 3) {
        const double a = signed_area(pos[tris[t]], pos[tris[t + 1]], pos[tris[t + 2]], Vec3(0, 0, 1));
        EXPECT_GT(a, 0.1);
        sum += a;
        EXPECT_EQ(on[tris[t]] & on[tris[t + 1]] & on[tris[t + 2]], 0) << "three vertices on one edge";
    }
    EXPECT_DOUBLE_EQ(sum, 2.0);
}

// Far from the origin, a small piece's corners cannot be placed on an oblique edge more exactly
// than their coordinates' ulps: the tolerance must follow the coordinates' magnitude, not only
// the edge's length.
void expect_oblique_t_vertex_found(const Vec3& o, double s) {
    // Piece 0: triangle (a, b, c) with the oblique edge 0 a → b; pieces 1 and 2 meet at m on it.
    const Vec3 a = o, b = o + Vec3(s, s, 0), c = o + Vec3(0, s, 0), d = o + Vec3(s, 0, 0);
    Vec3 m = o + Vec3(s / 2, s / 2, 0);
    m.x = std::nextafter(std::nextafter(m.x, 1e300), 1e300);  // two ulps off the line
    const auto gs = numbered({tri(a, b, c), tri(a, d, m), tri(d, b, m)});
    // The premise: m is off the edge by more than 1e-6 of its length (a tolerance of the edge
    // alone would miss it) and within edge_tolerance.
    const Vec3 ab = b - a, am = m - a;
    const double off = glm::length(am - ab * (glm::dot(am, ab) / glm::dot(ab, ab)));
    if (glm::length(o) > 1) {
        EXPECT_GT(off, 1e-6 * glm::length(ab));
    }
    EXPECT_LT(off, edge_tolerance(a, b));

    std::vector<Vec3> corners;
    const auto tv = find_edge_vertices(gs, corners);
    ASSERT_EQ(tv.size(), 1u) << "at " << o.x;
    EXPECT_EQ(tv[0].g, 0u);
    EXPECT_EQ(tv[0].k, 0u);
    EXPECT_NEAR(tv[0].t, 0.5, 1e-3);
    EXPECT_EQ(corners[tv[0].at], m);
    const ScenePieces sp = prepare_pieces(gs);
    // Piece 0's outline now runs through m: it gains the sliver a, m, b.
    const double sliver = std::abs(signed_area(a, b, m, Vec3(0, 0, 1)));
    EXPECT_LE(sliver, 0.5 * edge_tolerance(a, b) * glm::length(ab));
    expect_covers_exactly(sp, gs[0], 0, 1, 1.01 * sliver);
    for (std::uint32_t g = 1; g < 3; ++g) expect_covers_exactly(sp, gs[g], g, 0);
}

TEST(Pieces, TVertexFoundNearTheOrigin) { expect_oblique_t_vertex_found(Vec3(0.0), 1e-6); }
TEST(Pieces, TVertexFoundFarFromTheOrigin) { expect_oblique_t_vertex_found(Vec3(1e5, 1e5, 0), 1e-6); }
TEST(Pieces, TVertexOfTheUsualSizeFoundFarFromTheOrigin) {
    const auto gs = long_and_two_short(Vec3(1e5, -1e5, 1e5), 0.5);
    std::vector<Vec3> corners;
    const auto tv = find_edge_vertices(gs, corners);
    ASSERT_EQ(tv.size(), 1u);
    EXPECT_EQ(tv[0].g, 0u);
    EXPECT_EQ(tv[0].k, 2u);
}

// A small parallelogram far away whose fourth corner is off by an ulp is still drawn as a
// parallelogram (kind 5: cell coordinates, no inverse bilinear); a visibly bent quad is not.
TEST(Pieces, ParallelogramFarFromTheOriginKeepsItsKind) {
    const Vec3 o(1e5, 1e5, 1e5);
    const double s = 1e-6;
    Vec3 c2 = o + Vec3(s, s, 0);
    c2.y = std::nextafter(c2.y, 1e300);
    const ScenePieces far = prepare_pieces(numbered({quad(o, o + Vec3(s, 0, 0), c2, o + Vec3(0, s, 0))}));
    EXPECT_EQ(far.gpu[0].count, 5u);
    const ScenePieces bent = prepare_pieces(numbered({quad(o, o + Vec3(s, 0, 0), o + Vec3(s, 1.5 * s, 0), o + Vec3(0, s, 0))}));
    EXPECT_EQ(bent.gpu[0].count, 4u);
}


// The six inward walls of the box [0,1]³ (floor first), shifted by o.
std::vector<PatchGrid> inward_box(const Vec3& o) {
    const auto p = [&](double x, double y, double z) { return o + Vec3(x, y, z); };
    return {quad(p(0, 0, 0), p(1, 0, 0), p(1, 1, 0), p(0, 1, 0)),   // floor, +z
            quad(p(0, 0, 1), p(0, 1, 1), p(1, 1, 1), p(1, 0, 1)),   // ceiling, -z
            quad(p(0, 0, 0), p(0, 1, 0), p(0, 1, 1), p(0, 0, 1)),   // x = 0, +x
            quad(p(1, 0, 0), p(1, 0, 1), p(1, 1, 1), p(1, 1, 0)),   // x = 1, -x
            quad(p(0, 0, 0), p(0, 0, 1), p(1, 0, 1), p(1, 0, 0)),   // y = 0, +y
            quad(p(0, 1, 0), p(1, 1, 0), p(1, 1, 1), p(0, 1, 1))};  // y = 1, -y
}

std::vector<PatchGrid> with(std::vector<PatchGrid> a, const std::vector<PatchGrid>& b) {
    a.insert(a.end(), b.begin(), b.end());
    return numbered(a);
}

// The walls of a closed box are its enclosure, a two-sided plate inside it is not; the eye test
// is strict. Near the origin and 1e5 away from it (the tolerance follows the coordinates).
TEST(Enclosure, ClosedBoxWallsAroundAPlate) {
    for (const Vec3 o : {Vec3(0.0), Vec3(1e5, -2e5, 3e5)}) {
        const auto q = [&](double x, double y, double z) { return o + Vec3(x, y, z); };
        const auto gs = with(inward_box(o), {quad(q(.25, .25, .5), q(.75, .25, .5), q(.75, .75, .5), q(.25, .75, .5)),
                                             quad(q(.25, .25, .5), q(.25, .75, .5), q(.75, .75, .5), q(.75, .25, .5))});
        const Enclosure e = find_enclosure(gs);
        ASSERT_EQ(e.planes.size(), 6u);
        EXPECT_EQ(e.piece, (std::vector<std::uint8_t>{1, 1, 1, 1, 1, 1, 0, 0}));
        EXPECT_GT(e.tolerance, 0);
        EXPECT_LT(e.tolerance, 1e-8);
        EXPECT_TRUE(e.contains(q(.5, .5, .5)));
        EXPECT_TRUE(e.contains(q(1e-6, .5, .5)));
        EXPECT_FALSE(e.contains(q(0, .5, .5))) << "on a wall: not strictly inside";
        EXPECT_FALSE(e.contains(q(.5, .5, 1 + 1e-6)));
        EXPECT_FALSE(e.contains(q(-3, .5, .5)));
    }
}

// Seen from outside, a box's faces overlap: an outward box has no enclosure, nor has a single
// plate (nothing to enclose).
TEST(Enclosure, OutwardBoxAndLonePlateHaveNone) {
    std::vector<PatchGrid> out = inward_box(Vec3(0.0));
    for (PatchGrid& g : out) std::swap(g.corners[1], g.corners[3]);  // every face turned over
    EXPECT_TRUE(find_enclosure(numbered(out)).planes.empty());
    EXPECT_TRUE(find_enclosure(numbered(out)).piece.empty());
    EXPECT_TRUE(find_enclosure(numbered({quad(Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(1, 1, 0), Vec3(0, 1, 0))})).planes.empty());
}

// A piece lying on the floor facing down would tie in depth with the floor, and the depth test
// decided: the floor's plane is left out, the others stay. One facing up joins the floor's plane
// (drawn in reverse piece order, the floor, first, still wins where they overlap).
TEST(Enclosure, APieceLyingOnTheFloor) {
    const Vec3 a(.2, .2, 0), b(.4, .2, 0), c(.4, .4, 0), d(.2, .4, 0);
    Enclosure e = find_enclosure(with(inward_box(Vec3(0.0)), {quad(a, d, c, b)}));
    EXPECT_EQ(e.planes.size(), 5u);
    EXPECT_EQ(e.piece, (std::vector<std::uint8_t>{0, 1, 1, 1, 1, 1, 0}));
    e = find_enclosure(with(inward_box(Vec3(0.0)), {quad(a, b, c, d)}));
    EXPECT_EQ(e.planes.size(), 6u);
    EXPECT_EQ(e.piece, (std::vector<std::uint8_t>{1, 1, 1, 1, 1, 1, 1}));
    // A block standing on the floor touches it along edges only: the floor stays.
    const Vec3 A(.2, .2, .3), B(.4, .2, .3), C(.4, .4, .3), D(.2, .4, .3);
    e = find_enclosure(with(inward_box(Vec3(0.0)), {quad(A, B, C, D), quad(a, b, B, A), quad(b, c, C, B),
                                                                    quad(c, d, D, C), quad(d, a, A, D)}));
    EXPECT_EQ(e.planes.size(), 6u);
    EXPECT_EQ(e.piece, (std::vector<std::uint8_t>{1, 1, 1, 1, 1, 1, 0, 0, 0, 0, 0}));
}

// The other pieces of a closed box need no depth test when they lie in one plane and either
// face one way or come in twins (a two-sided plate): only one of each twin pair is drawn.
TEST(Enclosure, InnerPiecesInOnePlaneNeedNoDepthTest) {
    const Vec3 a(.2, .2, .5), b(.8, .2, .5), c(.8, .8, .5), d(.2, .8, .5), e(.2, .2, .7), f(.8, .2, .7);
    const auto box = inward_box(Vec3(0.0));
    const auto flat = [&](const std::vector<PatchGrid>& inner) {
        const auto gs = with(box, inner);
        return find_enclosure(gs, find_twins(gs)).inner_flat;
    };
    EXPECT_TRUE(flat({})) << "an empty room";
    EXPECT_TRUE(flat({quad(a, b, c, d), quad(a, d, c, b)})) << "a two-sided plate";
    EXPECT_TRUE(flat({quad(a, b, c, d), quad(Vec3(.2, .85, .5), Vec3(.8, .85, .5), Vec3(.8, .95, .5), Vec3(.2, .95, .5))}))
        << "two one-sided pieces of one plane, facing up";
    EXPECT_FALSE(flat({quad(a, b, c, d), tri(a + Vec3(0, .1, 0), c, b)})) << "one up, one down, no twins";
    EXPECT_FALSE(flat({quad(a, b, c, d), quad(a, b, f, e)})) << "two planes";
    // Without the twins given, a two-sided plate is two pieces facing apart.
    const auto gs = with(box, {quad(a, b, c, d), quad(a, d, c, b)});
    EXPECT_FALSE(find_enclosure(gs).inner_flat);
}

// A closed box is a closed enclosure (its hemicubes need no clear); without its ceiling, or with a
// wall cut in two (whose middle corners lie inside the neighbours' edges), it is not.
TEST(Enclosure, ClosedOnlyWhenEveryEdgeIsSharedTheOtherWayRound) {
    auto box = inward_box(Vec3(0.0));
    EXPECT_TRUE(find_enclosure(numbered(box)).closed);
    EXPECT_TRUE(find_enclosure(with(box, {quad(Vec3(.2, .2, .5), Vec3(.8, .2, .5), Vec3(.8, .8, .5), Vec3(.2, .8, .5))})).closed)
        << "a plate inside does not open it";
    auto open = box;
    open.erase(open.begin() + 1);  // the ceiling
    const Enclosure e = find_enclosure(numbered(open));
    EXPECT_EQ(e.planes.size(), 5u);
    EXPECT_FALSE(e.closed);
    auto cut = box;
    cut[0] = quad(Vec3(0, 0, 0), Vec3(.5, 0, 0), Vec3(.5, 1, 0), Vec3(0, 1, 0));  // the floor in two halves
    cut.push_back(quad(Vec3(.5, 0, 0), Vec3(1, 0, 0), Vec3(1, 1, 0), Vec3(.5, 1, 0)));
    const Enclosure c = find_enclosure(numbered(cut));
    EXPECT_EQ(c.planes.size(), 6u);
    EXPECT_FALSE(c.closed) << "(.5, 0, 0) and (.5, 1, 0) lie inside the walls' edges";
}

// A city: the ground's tiles (one plane, pieces in any order) under buildings; walls and roofs are
// not supporting.
TEST(Enclosure, TheGroundOfACity) {
    std::vector<PatchGrid> gs;
    for (int i = 0; i < 3; ++i)
        gs.push_back(tri(Vec3(i, 0, 0), Vec3(i + 1, 0, 0), Vec3(i + 1, 1, 0)));
    const Vec3 a(.2, .2, 0), b(.6, .2, 0), A(.2, .2, 2), B(.6, .2, 2);
    gs.push_back(quad(a, b, B, A));                                                 // a wall, -y
    gs.push_back(quad(A, B, B + Vec3(0, .4, 0), A + Vec3(0, .4, 0)));               // a roof, +z
    gs.push_back(tri(Vec3(5, 5, 0), Vec3(6, 5, 0), Vec3(6, 6, 0)));                 // more ground
    Enclosure e = find_enclosure(numbered(gs));
    ASSERT_EQ(e.planes.size(), 1u);
    EXPECT_NEAR(e.planes[0].normal.z, 1.0, 1e-15);
    EXPECT_EQ(e.piece, (std::vector<std::uint8_t>{1, 1, 1, 0, 0, 1}));
    EXPECT_TRUE(e.contains(Vec3(100, 100, 1e-6)));
    EXPECT_FALSE(e.contains(Vec3(100, 100, -1e-6)));
    // One corner a thousandth below the ground: no plane has the whole city in front of it.
    gs[5] = tri(Vec3(5, 5, 0), Vec3(6, 5, 0), Vec3(6, 6, -1e-3));
    e = find_enclosure(numbered(gs));
    EXPECT_TRUE(e.planes.empty());
    EXPECT_TRUE(e.piece.empty());
    // A quad bent a thousandth up out of the ground's plane: the ground still supports the city;
    // the bent quad is no enclosure piece (not planar), nor does it lie in the ground's plane.
    gs[5] = quad(Vec3(5, 5, 0), Vec3(6, 5, 0), Vec3(6, 6, 1e-3), Vec3(5, 6, 0));
    e = find_enclosure(numbered(gs));
    EXPECT_EQ(e.planes.size(), 1u);
    EXPECT_EQ(e.piece, (std::vector<std::uint8_t>{1, 1, 1, 0, 0, 0}));
}

}  // namespace
}  // namespace ffcube
