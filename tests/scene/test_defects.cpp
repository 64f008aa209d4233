// Defects found before meshing (include/ffcube/scene/defects.hpp; docs/robustness.md,
// "Defective geometry"): duplicate faces removed, crossing faces and bow-ties refused naming the
// file line, and a scene far from its origin recentred exactly. Every input is generated here.
#include <gtest/gtest.h>

#include <fmt/format.h>

#include <glm/geometric.hpp>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <string>
#include <vector>

#include "ffcube/scene/defects.hpp"
#include "ffcube/scene/load_model.hpp"
#include "ffcube/scene/mesher.hpp"
#include "ffcube/scene/polygons.hpp"
#include "support/scenes.hpp"
#include "support/temp_files.hpp"

namespace ffcube {
namespace {

using test::inward_box;
using test::TempFiles;

// A binary STL of the triangles (each given CCW from the front), every facet written `copies` times.
std::string binary_stl(const std::vector<std::array<Vec3, 3>>& tris, int copies) {
    std::string out(80, '\0');
    const auto put_u32 = [&](std::uint32_t v) { out.append(reinterpret_cast<const char*>(&v), 4); };
    const auto put_f32 = [&](double v) {
        const float f = static_cast<float>(v);
        out.append(reinterpret_cast<const char*>(&f), 4);
    };
    put_u32(static_cast<std::uint32_t>(tris.size() * copies));
    for (const auto& t : tris)
        for (int c = 0; c < copies; ++c) {
            for (int k = 0; k < 3; ++k) put_f32(0);
            for (const Vec3& v : t) put_f32(v.x), put_f32(v.y), put_f32(v.z);
            out.append(2, '\0');
        }
    return out;
}

std::vector<std::array<Vec3, 3>> triangles(const std::vector<NamedPolygon>& polys) {
    std::vector<std::array<Vec3, 3>> t;
    for (const NamedPolygon& p : polys) {
        t.push_back({p.vertices[0], p.vertices[1], p.vertices[2]});
        t.push_back({p.vertices[0], p.vertices[2], p.vertices[3]});
    }
    return t;
}

double total_area(const ObjModel& m) {
    return build_scene(m, MeshOptions{.max_patch_edge = 10.0}).total_area();
}

TEST(Defects, EveryFacetOfABinaryStlTwiceIsTheSingleBox) {
    TempFiles dir;
    const auto tris = triangles(inward_box(1, 1, 1));
    ObjModel twice = load_model(dir.write("box2.stl", binary_stl(tris, 2)));
    ObjModel once = load_model(dir.write("box1.stl", binary_stl(tris, 1)));
    ASSERT_EQ(twice.faces.size(), 24u);
    const DefectStats st = check_defects(twice);
    EXPECT_EQ(st.duplicates_removed, 12u);
    EXPECT_EQ(st.two_sided_pairs, 0u);
    ASSERT_EQ(st.warnings.size(), 1u);
    // Binary STL faces are named by facet number: facet 2 repeats facet 1.
    EXPECT_NE(st.warnings[0].find("box2.stl: facet 2 (object 'box2') repeats "), std::string::npos) << st.warnings[0];
    EXPECT_NE(st.warnings[0].find("removed 12 duplicate faces"), std::string::npos) << st.warnings[0];
    ASSERT_EQ(twice.faces.size(), once.faces.size());
    for (std::size_t f = 0; f < once.faces.size(); ++f) EXPECT_EQ(twice.faces[f].v, once.faces[f].v);
    // The independent fact: the surface is the unit cube's, area 6 (not 12).
    EXPECT_NEAR(total_area(twice), 6.0, 1e-12);
}

TEST(Defects, AFacetThreeTimesInAsciiStlAndAWallTwiceInVs3) {
    TempFiles dir;
    const auto tris = triangles(inward_box(1, 1, 1));
    std::string ascii = "solid box\n";
    for (std::size_t k = 0; k < tris.size(); ++k)
        for (int c = 0; c < (k == 0 ? 3 : 1); ++c) {
            ascii += " facet normal 0 0 0\n  outer loop\n";
            for (const Vec3& v : tris[k]) ascii += fmt::format("   vertex {} {} {}\n", v.x, v.y, v.z);
            ascii += "  endloop\n endfacet\n";
        }
    ascii += "endsolid box\n";
    ObjModel m = load_model(dir.write("box3.stl", ascii));
    const DefectStats st = check_defects(m);
    EXPECT_EQ(st.duplicates_removed, 2u);
    // The copies begin on lines 9 and 16 (7 lines a facet after "solid" on line 1).
    EXPECT_NE(st.warnings.at(0).find("box3.stl:9 (object 'box') repeats "), std::string::npos) << st.warnings[0];
    EXPECT_NE(st.warnings.at(0).find("box3.stl:16 (object 'box') repeats "), std::string::npos) << st.warnings[0];
    EXPECT_NE(st.warnings.at(0).find("box3.stl:2 (object 'box')"), std::string::npos) << st.warnings[0];
    EXPECT_NEAR(total_area(m), 6.0, 1e-12);

    std::string vs3 = "T box\nF 3\n";
    const auto box = inward_box(1, 1, 1);
    int v = 0;
    for (const auto& p : box)
        for (const Vec3& x : p.vertices) vs3 += fmt::format("V {} {} {} {}\n", ++v, x.x, x.y, x.z);
    for (int s = 0; s < 7; ++s) {
        const int base = (s == 6 ? 0 : s) * 4;  // surface 7 repeats surface 1's vertices
        vs3 += fmt::format("S {} {} {} {} {} 0 0 0.5 w{}\n", s + 1, base + 1, base + 2, base + 3, base + 4, s + 1);
    }
    vs3 += "End of data\n";
    ObjModel w = load_model(dir.write("box.vs3", vs3));
    const DefectStats sw = check_defects(w);
    EXPECT_EQ(sw.duplicates_removed, 1u);
    EXPECT_NE(sw.warnings.at(0).find("(object 'w7') repeats"), std::string::npos) << sw.warnings[0];
    EXPECT_NEAR(total_area(w), 6.0, 1e-12);
}

// Coordinates that differ by rounding only (within the tolerance, 1e-9 of the size) are the same
// vertex; beyond it they are not.
TEST(Defects, DuplicatesWithinTheToleranceOnlyAndTwoSidedSheetsStay) {
    std::vector<NamedPolygon> polys = inward_box(1, 1, 1);
    NamedPolygon plate{"plate", {{0.3, 0.3, 0.5}, {0.7, 0.3, 0.5}, {0.7, 0.7, 0.5}, {0.3, 0.7, 0.5}}};
    NamedPolygon back{"back", {plate.vertices.rbegin(), plate.vertices.rend()}};
    NamedPolygon near_copy = plate;
    near_copy.object = "near_copy";
    for (Vec3& x : near_copy.vertices) x += Vec3(3e-10, -2e-10, 1e-10);  // |shift| 3.7e-10 < 1e-9 × √3
    NamedPolygon rotated = plate;  // the same cycle begun at another vertex
    rotated.object = "rotated";
    std::rotate(rotated.vertices.begin(), rotated.vertices.begin() + 2, rotated.vertices.end());
    NamedPolygon apart = plate;
    apart.object = "apart";
    for (Vec3& x : apart.vertices) x.z += 1e-6;  // 1e-6: a real plate above, not a copy
    polys.insert(polys.end(), {plate, back, near_copy, rotated, apart});
    ObjModel m = model_from_polygons(polys, "<plates>");
    EXPECT_NEAR(coincidence_tolerance(m), 1e-9 * std::sqrt(3.0), 1e-20);
    const DefectStats st = check_defects(m);
    EXPECT_EQ(st.duplicates_removed, 2u);  // near_copy and rotated
    EXPECT_EQ(st.two_sided_pairs, 1u);     // back stays
    ASSERT_EQ(m.faces.size(), 9u);
    std::vector<std::string> left;
    for (const ObjFace& f : m.faces) left.push_back(m.objects[f.object]);
    EXPECT_EQ(left, (std::vector<std::string>{"z0", "z1", "x0", "x1", "y0", "y1", "plate", "back", "apart"}));
}

TEST(Defects, FacesThatPassThroughEachOtherAreRefusedByName) {
    std::vector<NamedPolygon> polys = inward_box(1, 1, 1);
    polys.push_back({"plateA", {{0.2, 0.5, 0.2}, {0.8, 0.5, 0.2}, {0.8, 0.5, 0.8}, {0.2, 0.5, 0.8}}});
    polys.push_back({"plateB", {{0.5, 0.2, 0.2}, {0.5, 0.8, 0.2}, {0.5, 0.8, 0.8}, {0.5, 0.2, 0.8}}});
    ObjModel m = model_from_polygons(polys, "crossing.obj");
    const std::string e = test::input_error_of([&] { check_defects(m); });
    EXPECT_NE(e.find("crossing.obj:"), std::string::npos) << e;
    EXPECT_NE(e.find("crossing.obj:7 (object 'plateA') and crossing.obj:8 (object 'plateB')"), std::string::npos) << e;
    EXPECT_NE(e.find("pass through each other"), std::string::npos) << e;
    // The crossing is the segment x = y = 0.5, z from 0.2 to 0.8: 0.6 long.
    EXPECT_NE(e.find("(object 'plateB') (along 0.6)"), std::string::npos) << e;

    // A plate poking through the floor is crossing too (named by the floor's line).
    std::vector<NamedPolygon> poke = inward_box(1, 1, 1);
    poke.push_back({"poke", {{0.3, 0.4, -0.2}, {0.7, 0.4, -0.2}, {0.7, 0.4, 0.5}, {0.3, 0.4, 0.5}}});
    ObjModel p = model_from_polygons(poke, "poke.obj");
    EXPECT_NE(test::input_error_of([&] { check_defects(p); }).find("poke.obj:1 (object 'z0') and poke.obj:7 (object 'poke')"),
              std::string::npos);
}

// Touching is not crossing: a box's walls meeting at edges, a plate standing on the floor
// (its edge on the floor's plane), a two-sided plate, a plate lying on the floor (coplanar),
// a fin meeting a wall in a T.
TEST(Defects, TouchingFacesAreNotCrossing) {
    std::vector<NamedPolygon> polys = inward_box(1, 1, 1);
    const auto fin = test::floor_wall_fin();
    polys.insert(polys.end(), fin.begin() + 2, fin.end());
    polys.push_back({"lying", {{0.6, 0.6, 0}, {0.9, 0.6, 0}, {0.9, 0.9, 0}, {0.6, 0.9, 0}}});
    polys.push_back({"t", {{0.0, 0.7, 0.2}, {0.5, 0.7, 0.2}, {0.5, 0.7, 0.6}, {0.0, 0.7, 0.6}}});  // edge on the wall x = 0
    ObjModel m = model_from_polygons(polys, "<touching>");
    EXPECT_EQ(refuse_crossing_faces(m), 0u);
    // Sunk below the floor by 2e-7 (within 1e-6 of its size: the floor's planarity tolerance):
    // still standing on it; by 1e-3: through it.
    for (const double sink : {2e-7, 1e-3}) {
        std::vector<NamedPolygon> q = inward_box(1, 1, 1);
        q.push_back({"post", {{0.4, 0.5, -sink}, {0.6, 0.5, -sink}, {0.6, 0.5, 0.5}, {0.4, 0.5, 0.5}}});
        ObjModel s = model_from_polygons(q, "<sunk>");
        if (sink < 1e-6)
            EXPECT_EQ(refuse_crossing_faces(s), 0u);
        else
            EXPECT_NE(test::input_error_of([&] { refuse_crossing_faces(s); }).find("pass through"), std::string::npos);
    }
}

// A bow-tie quad: its hull has area 3 (what the mesher made of it before), its two triangles
// 2 × 5/6 = 1.667 (they meet at (1.2, 0.6)); refused, naming the line and the crossing edges.
TEST(Defects, ABowTieIsRefusedNamingTheLine) {
    TempFiles dir;
    const std::string vs3 =
        "T bow-tie\nF 3\nV 1 0 0 0\nV 2 3 0 0\nV 3 0 1 0\nV 4 3 1 0\nV 5 0 0 1\nV 6 3 0 1\nV 7 3 1 1\nV 8 0 1 1\n"
        "S 1 1 2 3 4 0 0 0.5 floor\nS 2 5 6 7 8 0 0 0.5 top\nEnd of data\n";
    ObjModel m = load_model(dir.write("bowtie.vs3", vs3));
    const std::string e = test::input_error_of([&] { check_defects(m); });
    EXPECT_NE(e.find("bowtie.vs3:11: this face of 4 vertices crosses itself (its edges 2-3 and 4-1 cross: a bow-tie), in "
                     "object 'floor'"),
              std::string::npos)
        << e;
    // The independent fact behind the refusal: walking the face, its two lobes are v1 v2 x and
    // x v3 v4 with x = (1.5, 0.5) where the edges cross: areas 0.75 each (not the hull's 3), facing
    // opposite ways (their signed areas cancel).
    const std::vector<Vec3> lobe1{{0, 0, 0}, {3, 0, 0}, {1.5, 0.5, 0}}, lobe2{{1.5, 0.5, 0}, {0, 1, 0}, {3, 1, 0}};
    EXPECT_NEAR(polygon_area(lobe1), 0.75, 1e-15);
    EXPECT_NEAR(polygon_area(lobe2), 0.75, 1e-15);
    EXPECT_LT(glm::dot(polygon_normal(lobe1), polygon_normal(lobe2)), 0.0);
    // A convex quad and a non-convex (L-shaped) hexagon are not bow-ties.
    ObjModel ok = model_from_polygons({{"l", {{0, 0, 0}, {2, 0, 0}, {2, 1, 0}, {1, 1, 0}, {1, 2, 0}, {0, 2, 0}}}}, "<l>");
    EXPECT_NO_THROW(refuse_self_intersecting_faces(ok));
}

// Far from the origin the model is moved by its box's centre, exactly; near it, not at all.
TEST(Defects, RecentringIsExactAndOnlyFarFromTheOrigin) {
    for (const double x0 : {1e5, 1e12, 1e14}) {
        std::vector<NamedPolygon> polys = inward_box(1, 1, 1);
        for (NamedPolygon& p : polys)
            for (Vec3& v : p.vertices) v.x += x0;
        ObjModel m = model_from_polygons(polys, "<far>");
        const std::vector<Vec3> before = m.positions;
        const Vec3 origin = recentre(m);
        EXPECT_EQ(origin, Vec3(x0 + 0.5, 0, 0));
        for (std::size_t k = 0; k < before.size(); ++k) {
            EXPECT_EQ(m.positions[k] + origin, before[k]);   // nothing lost
            EXPECT_EQ(std::abs(m.positions[k].x), 0.5);  // exactly the box at the origin
        }
    }
    ObjModel near = model_from_polygons(inward_box(555, 555, 555), "<near>");
    const std::vector<Vec3> before = near.positions;
    EXPECT_EQ(recentre(near), Vec3(0.0));
    EXPECT_EQ(near.positions, before);
}

}  // namespace
}  // namespace ffcube
