// Contact cuts (scene/contact.hpp): a receiver face is cut along the polygon where another object
// stands on it, so that no face straddles the contact line; areas are kept, the covered area is
// the footprint's (shoelace of its corners), and only closed convex contacts of other objects cut.
#include <gtest/gtest.h>

#include <glm/geometric.hpp>
#include <glm/vec2.hpp>

#include <algorithm>

#include <cmath>

#include "ffcube/geometry/polygon.hpp"
#include "ffcube/scene/builtin.hpp"
#include "ffcube/scene/contact.hpp"
#include "ffcube/scene/mesher.hpp"

namespace ffcube {
namespace {

std::uint32_t add_object(ObjModel& m, const std::string& name) {
    m.objects.push_back(name);
    return static_cast<std::uint32_t>(m.objects.size() - 1);
}

void add_face(ObjModel& m, std::uint32_t object, const std::vector<Vec3>& poly) {
    ObjFace f;
    f.object = object;
    f.line = static_cast<std::uint32_t>(m.faces.size() + 1);
    for (const Vec3& p : poly) {
        f.v.push_back(static_cast<std::uint32_t>(m.positions.size()));
        m.positions.push_back(p);
    }
    m.faces.push_back(f);
}

// The floor y = 0, x, z in [0, 10], facing up (+y).
ObjModel floor_model() {
    ObjModel m;
    m.source = "test";
    m.materials.push_back(Material{});
    const auto floor = add_object(m, "floor");
    add_face(m, floor, {Vec3(0, 0, 0), Vec3(0, 0, 10), Vec3(10, 0, 10), Vec3(10, 0, 0)});
    return m;
}

// A box of height h over the footprint `base` (x, z corners counter-clockwise seen from above):
// outward side faces and a top, and a bottom face when asked (facing down).
void add_box(ObjModel& m, const std::string& name, const std::vector<glm::dvec2>& base, double h, bool bottom) {
    const auto o = add_object(m, name);
    const std::size_t n = base.size();
    // Counter-clockwise seen from above (+y) means clockwise in (x, z) as drawn: with x right and z
    // up in the plot, +y points into the page. Sides wound so that their normals point outward.
    for (std::size_t i = 0; i < n; ++i) {
        const glm::dvec2 a = base[i], b = base[(i + 1) % n];
        add_face(m, o, {Vec3(a.x, 0, a.y), Vec3(a.x, h, a.y), Vec3(b.x, h, b.y), Vec3(b.x, 0, b.y)});
    }
    std::vector<Vec3> top, bot;
    for (std::size_t i = 0; i < n; ++i) top.push_back(Vec3(base[i].x, h, base[i].y));
    for (std::size_t i = n; i-- > 0;) bot.push_back(Vec3(base[i].x, 0, base[i].y));
    if (polygon_normal(top).y < 0) std::reverse(top.begin(), top.end());
    if (polygon_normal(bot).y > 0) std::reverse(bot.begin(), bot.end());
    add_face(m, o, top);
    if (bottom) add_face(m, o, bot);
}

double shoelace(const std::vector<glm::dvec2>& p) {
    double s = 0;
    for (std::size_t i = 0; i < p.size(); ++i) s += p[i].x * p[(i + 1) % p.size()].y - p[(i + 1) % p.size()].x * p[i].y;
    return std::abs(0.5 * s);
}

// Point-in-convex-polygon (x, z), closed within eps.
bool inside(const std::vector<glm::dvec2>& poly, glm::dvec2 q, double eps) {
    double sign = 0;
    for (std::size_t i = 0; i < poly.size(); ++i) {
        const glm::dvec2 a = poly[i], b = poly[(i + 1) % poly.size()];
        const double c = (b.x - a.x) * (q.y - a.y) - (b.y - a.y) * (q.x - a.x);
        const double len = glm::length(b - a);
        if (std::abs(c) <= eps * len) continue;
        if (sign == 0) sign = c;
        if (c * sign < 0) return false;
    }
    return true;
}

std::vector<Vec3> face_poly(const ObjModel& m, const ObjFace& f) {
    std::vector<Vec3> p;
    for (auto v : f.v) p.push_back(m.positions[v]);
    return p;
}

// The floor's faces after the cut: total area kept (rounding of a few ulps of 100 per face); no
// face straddles the footprint (every vertex of a face whose centroid is inside lies inside, within
// 1e-9 of the edges: the cut points are computed to rounding, ~1e-15 × 10); the covered area is the
// footprint's.
void expect_cut_along(const ObjModel& m, std::uint32_t floor, const std::vector<glm::dvec2>& footprint) {
    double total = 0, covered = 0;
    for (const ObjFace& f : m.faces) {
        if (f.object != floor) continue;
        const std::vector<Vec3> p = face_poly(m, f);
        EXPECT_GT(polygon_normal(p).y, 1 - 1e-12);
        const double a = polygon_area(p);
        total += a;
        const Vec3 c = polygon_centroid(p);
        const bool in = inside(footprint, {c.x, c.z}, -1e-9);  // strictly inside: away from edges
        bool all_in = true;
        for (const Vec3& v : p) {
            all_in = all_in && inside(footprint, {v.x, v.z}, 1e-9);
        }
        // A face outside the footprint has its centroid outside; its vertices may lie on the edge.
        if (in) {
            EXPECT_TRUE(all_in) << "a covered face leaves the footprint";
            covered += a;
        } else {
            EXPECT_FALSE(inside(footprint, {c.x, c.z}, 1e-9)) << "a face's centroid lies on the contact line";
        }
    }
    EXPECT_NEAR(total, 100.0, 1e-12 * 100 * 20);
    EXPECT_NEAR(covered, shoelace(footprint), 1e-12 * 100 * 20);
}

TEST(ContactCuts, BlockWithoutBottomCutsTheFloorAlongItsFootprint) {
    ObjModel m = floor_model();
    // A rotated block (not aligned with the floor's edges), as the Cornell box's.
    const std::vector<glm::dvec2> base{{3, 2}, {2.2, 4.6}, {4.8, 5.4}, {5.6, 2.8}};
    add_box(m, "block", base, 1.5, false);
    const ContactCutStats s = cut_contacts(m);
    EXPECT_EQ(s.contacts, 1u);
    EXPECT_EQ(s.receivers, 1u);
    EXPECT_EQ(s.skipped, 0u);
    EXPECT_NEAR(s.covered_area, shoelace(base), 1e-12 * 100);
    EXPECT_GT(s.faces, 2u);
    expect_cut_along(m, 0, base);
    // The block's faces are untouched: the floor's edges do not make a loop in any of its planes.
    std::size_t block_faces = 0;
    for (const ObjFace& f : m.faces) block_faces += f.object == 1 ? 1 : 0;
    EXPECT_EQ(block_faces, 5u);
    // The cut model meshes (every face convex: no triangulated non-convex face, nothing dropped).
    const Scene scene = build_scene(m, MeshOptions{.max_patch_edge = 1.0});
    EXPECT_EQ(scene.stats.dropped_degenerate, 0u);
    double floor_area = 0;
    for (const Patch& p : scene.patches) floor_area += p.object == 0 ? p.area : 0.0;
    EXPECT_NEAR(floor_area, 100.0, 1e-9);
}

TEST(ContactCuts, ABottomFaceIsTheContactPolygon) {
    ObjModel m = floor_model();
    const std::vector<glm::dvec2> base{{3, 2}, {2.2, 4.6}, {4.8, 5.4}, {5.6, 2.8}};
    add_box(m, "block", base, 1.5, true);
    const ContactCutStats s = cut_contacts(m);
    EXPECT_EQ(s.contacts, 1u);
    EXPECT_NEAR(s.covered_area, shoelace(base), 1e-12 * 100);
    expect_cut_along(m, 0, base);
}

TEST(ContactCuts, TwoBlocksAndABlockOverTheEdgeAreClippedToTheFloor) {
    ObjModel m = floor_model();
    const std::vector<glm::dvec2> a{{1, 1}, {1, 3}, {3, 3}, {3, 1}};
    const std::vector<glm::dvec2> b{{8, 6}, {8, 12}, {12, 12}, {12, 6}};  // half off the floor
    add_box(m, "a", a, 1.0, false);
    add_box(m, "b", b, 1.0, false);
    const ContactCutStats s = cut_contacts(m);
    EXPECT_EQ(s.contacts, 2u);
    EXPECT_NEAR(s.covered_area, 4.0 + 2.0 * 4.0, 1e-12 * 100);
}

TEST(ContactCuts, OpenContactsSameObjectAndRaisedObjectsDoNotCut) {
    ObjModel m = floor_model();
    // A wall standing on the floor: one edge, no loop.
    const auto wall = add_object(m, "wall");
    add_face(m, wall, {Vec3(0, 0, 5), Vec3(0, 3, 5), Vec3(4, 3, 5), Vec3(4, 0, 5)});
    // A block floating 0.01 above the floor (1e-3 of the floor's size: far beyond the tolerance).
    ObjModel raised = m;
    std::vector<glm::dvec2> base{{6, 6}, {6, 8}, {8, 8}, {8, 6}};
    add_box(raised, "float", base, 1.0, false);
    for (std::size_t f = 2; f < raised.faces.size(); ++f)
        for (auto v : raised.faces[f].v) raised.positions[v].y += 0.01;
    const ContactCutStats s = cut_contacts(raised);
    EXPECT_EQ(s.contacts, 0u);
    EXPECT_EQ(raised.faces.size(), 2u + 5u);
    // The same block as part of the floor's own object: not a contact.
    ObjModel same = floor_model();
    add_box(same, "block", base, 1.0, false);
    for (auto& f : same.faces) f.object = 0;
    EXPECT_EQ(cut_contacts(same).contacts, 0u);
}

TEST(ContactCuts, ANonConvexContactIsLeftAloneAndCounted) {
    ObjModel m = floor_model();
    const std::vector<glm::dvec2> l{{1, 1}, {1, 5}, {3, 5}, {3, 3}, {5, 3}, {5, 1}};  // an L
    // Counter-clockwise from above in the sense add_box expects (same as the squares above).
    add_box(m, "l", l, 1.0, false);
    const ContactCutStats s = cut_contacts(m);
    EXPECT_EQ(s.contacts, 0u);
    EXPECT_EQ(s.skipped, 1u);
    ASSERT_EQ(s.notes.size(), 1u);
    EXPECT_NE(s.notes[0].find("'l'"), std::string::npos);
}

TEST(ContactCuts, CornellBoxFloorIsCutUnderBothBlocks) {
    ObjModel m = load_cornell_box();
    const ContactCutStats s = cut_contacts(m);
    EXPECT_EQ(s.contacts, 2u);
    EXPECT_EQ(s.receivers, 1u);  // the floor; walls touch the floor along one edge each
    // The blocks' footprints from the published data (examples/cornell_box.obj).
    const double short_block = shoelace({{130, 65}, {82, 225}, {240, 272}, {290, 114}});
    const double tall_block = shoelace({{423, 247}, {265, 296}, {314, 456}, {472, 406}});
    EXPECT_NEAR(s.covered_area, short_block + tall_block, 1e-12 * 559.2 * 556.0 * 20);
}

}  // namespace
}  // namespace ffcube
