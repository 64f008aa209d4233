// Meshing: patch counts for given edge bounds, area preserved, no patch edge above the bound,
// normals, n-gon triangulation, non-planar and degenerate faces, the patch-count target, the
// refusal of absurd meshes before allocating, and the fingerprint.
#include <gtest/gtest.h>

#include <fmt/format.h>
#include <glm/geometric.hpp>

#include <cmath>
#include <filesystem>
#include <functional>
#include <numbers>
#include <string>
#include <vector>

#include "ffcube/core/error.hpp"
#include "ffcube/scene/builtin.hpp"
#include "ffcube/scene/mesher.hpp"
#include "ffcube/scene/obj_loader.hpp"
#include "ffcube/scene/patch_areas.hpp"

namespace fs = std::filesystem;
using namespace ffcube;

namespace {

const fs::path kExamples = fs::path(FFCUBE_SOURCE_DIR) / "examples";

ObjModel parse(std::string_view text) {
    return parse_obj(text, "t.obj", [](const std::string&) { return std::optional<std::string>(); });
}

Scene mesh(const ObjModel& m, double max_edge) {
    MeshOptions o;
    o.max_patch_edge = max_edge;
    return build_scene(m, o);
}

// Summed area of the faces as the file gives them (Newell), an independent reference for the
// meshed area of planar faces.
double face_area(const ObjModel& m) {
    double sum = 0.0;
    for (const ObjFace& f : m.faces) {
        std::vector<Vec3> p;
        for (const auto i : f.v) p.push_back(m.positions[i]);
        sum += polygon_area(p);
    }
    return sum;
}

// Bilinear and barycentric grid vertices of faces with coordinates of magnitude up to |c| carry
// rounding errors of about 2 eps·|c| per coordinate (eps = 2.2e-16), so an edge length errs by
// at most 2·√3·2 eps·|c| < 4e-15·|c|. The mesher's own slack lets edges reach L·(1 + 1e-12).
void expect_edges_within(const Scene& s, double max_edge, double coordinate_scale = 1.0) {
    const double bound = max_edge * (1.0 + 1e-12) + 4e-15 * coordinate_scale;
    for (std::size_t i = 0; i < s.size(); ++i) {
        const auto v = s.patch_vertices(i);
        const std::uint32_t n = s.patches[i].count;
        for (std::uint32_t k = 0; k < n; ++k) ASSERT_LE(glm::length(v[(k + 1) % n] - v[k]), bound) << "patch " << i;
        ASSERT_LE(s.patches[i].size, bound);
    }
}

const char* kUnitSquare = "o a\nv 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf 1 2 3 4\n";

TEST(Mesher, UnitSquareGridCounts) {
    const ObjModel m = parse(kUnitSquare);
    // ceil(1/L) divisions per edge: 1/0.25 = 4, 1/0.3 → 4, 1/0.2 = 5, 1/0.5 = 2, 1/1 = 1.
    const std::pair<double, std::size_t> cases[] = {{0.25, 16}, {0.3, 16}, {0.2, 25}, {0.5, 4}, {1.0, 1}, {2.0, 1}, {0.1, 100}};
    for (const auto& [L, n] : cases) {
        EXPECT_EQ(count_patches(m, L), n) << "L = " << L;
        const Scene s = mesh(m, L);
        EXPECT_EQ(s.size(), n) << "L = " << L;
        const std::size_t side = static_cast<std::size_t>(std::lround(std::sqrt(static_cast<double>(n))));
        EXPECT_EQ(s.positions.size(), (side + 1) * (side + 1)) << "grid vertices are shared";
        expect_edges_within(s, L);
    }
}

TEST(Mesher, UnitSquareQuarterPatches) {
    const Scene s = mesh(parse(kUnitSquare), 0.25);
    ASSERT_EQ(s.size(), 16u);
    for (const Patch& p : s.patches) {
        EXPECT_EQ(p.count, 4u);
        // Each sub-square is 0.25 × 0.25 with corners on multiples of 0.25, exact in binary.
        EXPECT_EQ(p.area, 0.0625);
        EXPECT_EQ(p.normal, Vec3(0, 0, 1));
        EXPECT_EQ(p.size, 0.25);
        EXPECT_EQ(p.object, 0u);
        EXPECT_EQ(std::fmod(p.centroid.x, 0.25), 0.125);
    }
    // 16 exact areas of 1/16 sum exactly.
    EXPECT_EQ(s.total_area(), 1.0);
    EXPECT_EQ(patch_areas(s), std::vector<double>(16, 0.0625));  // each 0.25 × 0.25 exactly
    EXPECT_EQ(s.stats.triangulated_ngons, 0u);
    EXPECT_EQ(s.stats.how, "--max-patch-edge 0.25 (16 patches)");
    EXPECT_DOUBLE_EQ(s.extent(), std::sqrt(2.0));
}

TEST(Mesher, TriangleSplitsIntoSimilarTriangles) {
    const ObjModel m = parse("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n");
    // Longest edge √2 = 1.414: k = ceil(1.414/0.25) = 6 → 36 triangles, (k+1)(k+2)/2 = 28 vertices.
    const Scene s = mesh(m, 0.25);
    ASSERT_EQ(s.size(), 36u);
    EXPECT_EQ(s.positions.size(), 28u);
    for (std::size_t i = 0; i < s.size(); ++i) {
        const Patch& p = s.patches[i];
        EXPECT_EQ(p.count, 3u);
        EXPECT_EQ(p.v[3], p.v[2]);
        // Each is the original scaled by 1/6: area 0.5/36, to rounding of coordinates ≤ 1 (1e-15).
        EXPECT_NEAR(p.area, 0.5 / 36.0, 1e-15);
        EXPECT_NEAR(glm::length(p.normal - Vec3(0, 0, 1)), 0.0, 1e-15);
        EXPECT_NEAR(p.size, std::sqrt(2.0) / 6.0, 1e-15);
        EXPECT_EQ(s.patch_vertices(i)[3], s.patch_vertices(i)[2]);
    }
    // 36 areas, each within a few eps of 0.5/36: the sum is within ~36·4 eps of 0.5 (< 1e-13).
    EXPECT_NEAR(s.total_area(), 0.5, 1e-13);
    expect_edges_within(s, 0.25);
}

TEST(Mesher, QuadUsesTheLongerOfOppositeEdges) {
    // A trapezoid with bottom 2, top 1, height 1 (legs √1.25 = 1.118): L = 0.5 → u: ceil(2/0.5) = 4,
    // v: ceil(1.118/0.5) = 3 → 12 patches; area (2 + 1)/2 = 1.5.
    const ObjModel m = parse("v 0 0 0\nv 2 0 0\nv 1.5 1 0\nv 0.5 1 0\nf 1 2 3 4\n");
    const Scene s = mesh(m, 0.5);
    EXPECT_EQ(s.size(), 12u);
    EXPECT_EQ(count_patches(m, 0.5), 12u);
    // 12 sub-quad areas, each exact to a few eps·(area): relative 1e-14 is 50 eps.
    EXPECT_NEAR(s.total_area(), 1.5, 1.5e-14);
    expect_edges_within(s, 0.5);
    for (const Patch& p : s.patches) EXPECT_EQ(p.normal, Vec3(0, 0, 1));
}

TEST(Mesher, AreaPreservedAndEdgesBoundedOnExamples) {
    for (const char* name : {"parallel_squares.obj", "perpendicular_squares.obj", "cube.obj", "coaxial_disks.obj"}) {
        const ObjModel m = load_obj(kExamples / name);
        for (const double L : {0.5, 0.1, 0.037}) {
            const Scene s = mesh(m, L);
            EXPECT_EQ(s.size(), count_patches(m, L)) << name;
            // Planar faces tiled exactly: only rounding differs, n·eps relative at most (n ≤ 1e5
            // patches → 2e-11; compensated summation keeps the sum itself exact to eps).
            EXPECT_NEAR(s.total_area() / face_area(m), 1.0, 1e-11) << name << " L = " << L;
            expect_edges_within(s, L);
        }
    }
}

TEST(Mesher, ObjectsKeepTheirPatchesAndNormals) {
    const ObjModel m = load_obj(kExamples / "cube.obj");
    const Scene s = mesh(m, 0.5);
    ASSERT_EQ(s.objects.size(), 6u);
    ASSERT_EQ(s.size(), 24u);  // 2 × 2 per face
    std::vector<int> per_object(6, 0);
    for (const Patch& p : s.patches) {
        ++per_object[p.object];
        // Faces face inward: the normal points from the patch towards the cube's centre.
        const Vec3 to_centre = Vec3(0.5) - p.centroid;
        EXPECT_NEAR(glm::dot(p.normal, to_centre), 0.5, 1e-15) << s.objects[p.object];
        // The object's name says the axis: "x0" has normal +x.
        const std::string& name = s.objects[p.object];
        const int axis = name[0] - 'x';
        EXPECT_EQ(std::abs(p.normal[axis]), 1.0) << name;
    }
    for (int n : per_object) EXPECT_EQ(n, 4);
    EXPECT_DOUBLE_EQ(s.extent(), std::sqrt(3.0));
    EXPECT_EQ(s.bbox_min, Vec3(0));
    EXPECT_EQ(s.bbox_max, Vec3(1));
}

TEST(Mesher, ConvexNgonIsFannedFromItsCentroid) {
    // Regular hexagon of circumradius 1: area 3√3/2, six equilateral triangles of edge 1.
    std::string obj;
    for (int i = 0; i < 6; ++i) {
        const double t = i * std::numbers::pi / 3.0;
        obj += fmt::format("v {:.17g} {:.17g} 0\n", std::cos(t), std::sin(t));
    }
    obj += "f 1 2 3 4 5 6\n";
    const ObjModel m = parse(obj);
    const Scene one = mesh(m, 1.0 + 1e-9);
    EXPECT_EQ(one.size(), 6u);
    EXPECT_EQ(one.stats.triangulated_ngons, 1u);
    const Scene s = mesh(m, 0.1);  // k = 10 per triangle
    EXPECT_EQ(s.size(), 600u);
    // Vertex coordinates carry ~1e-16 errors: the area is exact to ~1e-15 relative.
    EXPECT_NEAR(s.total_area(), 1.5 * std::sqrt(3.0), 1e-13);
    for (const Patch& p : s.patches) EXPECT_NEAR(p.normal.z, 1.0, 1e-15);
    expect_edges_within(s, 0.1);
}

TEST(Mesher, NonConvexNgonIsEarClipped) {
    // An L-shape of area 3 (a 2 × 2 square without its upper-right unit square), counter-clockwise.
    const ObjModel m = parse("v 0 0 0\nv 2 0 0\nv 2 1 0\nv 1 1 0\nv 1 2 0\nv 0 2 0\nf 1 2 3 4 5 6\n");
    const Scene s = mesh(m, 10.0);
    EXPECT_EQ(s.stats.triangulated_ngons, 1u);
    EXPECT_EQ(s.size(), 4u);  // n − 2 triangles
    // A triangulation covers the polygon exactly once: the areas sum to 3, none is outside it.
    EXPECT_NEAR(s.total_area(), 3.0, 1e-14);
    for (const Patch& p : s.patches) {
        EXPECT_EQ(p.normal, Vec3(0, 0, 1));
        EXPECT_FALSE(p.centroid.x > 1.0 && p.centroid.y > 1.0) << "a triangle lies in the notch";
    }
    const Scene fine = mesh(m, 0.2);
    EXPECT_NEAR(fine.total_area(), 3.0, 1e-12);
    expect_edges_within(fine, 0.2);
}

TEST(Mesher, StarIsEarClippedWithoutOverlap) {
    // A five-pointed star: 10 vertices at 36° steps, radii alternating 1 and 0.4. Its area is 10
    // triangles (centre, two neighbours) of 0.5 · 1 · 0.4 · sin 36° each = 2 sin 36°.
    std::string obj;
    for (int i = 0; i < 10; ++i) {
        const double t = i * std::numbers::pi / 5.0, r = i % 2 == 0 ? 1.0 : 0.4;
        obj += fmt::format("v {:.17g} {:.17g} 0\n", r * std::cos(t), r * std::sin(t));
    }
    obj += "f 1 2 3 4 5 6 7 8 9 10\n";
    const Scene s = mesh(parse(obj), 10.0);
    EXPECT_EQ(s.size(), 8u);  // n − 2 triangles
    // Overlapping or missing triangles would change the sum by a whole triangle (≥ 1e-2); the
    // coordinates carry ~1e-16 errors.
    EXPECT_NEAR(s.total_area(), 2.0 * std::sin(std::numbers::pi / 5.0), 1e-14);
    for (const Patch& p : s.patches) EXPECT_NEAR(p.normal.z, 1.0, 1e-15) << "every triangle faces +z";
}

TEST(Mesher, NonConvexQuadIsTriangulated) {
    // A dart (0,0),(2,0),(1,2),(1,1): the corner at (1,1) is reflex. Area: triangle (0,0),(2,0),(1,2)
    // (2) minus the notch (0,0),(1,1),(1,2) (0.5) = 1.5.
    const ObjModel m = parse("v 0 0 0\nv 1 1 0\nv 2 0 0\nv 1 2 0\nf 1 3 4 2\n");
    const Scene s = mesh(m, 10.0);
    EXPECT_EQ(s.stats.triangulated_ngons, 1u);
    EXPECT_EQ(s.size(), 2u);
    EXPECT_NEAR(s.total_area(), 1.5, 1e-15);
}

TEST(Mesher, NonPlanarFaceIsCountedReportedAndTriangulated) {
    // Vertex 3 lifted by 0.1 over a face of size √2: far beyond 1e-6 of the size.
    const ObjModel m = parse("v 0 0 0\nv 1 0 0\nv 1 1 0.1\nv 0 1 0\n# a comment\nf 1 2 3 4\n");
    const Scene s = mesh(m, 10.0);
    EXPECT_EQ(s.stats.non_planar, 1u);
    EXPECT_EQ(s.stats.triangulated_ngons, 1u);
    EXPECT_EQ(s.size(), 2u);
    ASSERT_EQ(s.stats.warnings.size(), 1u);
    EXPECT_NE(s.stats.warnings[0].find("t.obj:6: face is not planar"), std::string::npos) << s.stats.warnings[0];

    // Lifted by 1e-7 instead: the deviation from the best-fit plane is 2.5e-8, within 1e-6 × size.
    const Scene flat = mesh(parse("v 0 0 0\nv 1 0 0\nv 1 1 1e-7\nv 0 1 0\nf 1 2 3 4\n"), 10.0);
    EXPECT_EQ(flat.stats.non_planar, 0u);
    EXPECT_EQ(flat.size(), 1u);
    EXPECT_EQ(flat.patches[0].count, 4u);
}

TEST(Mesher, DegenerateFacesAreDroppedAndCounted) {
    const ObjModel m = parse(std::string(kUnitSquare) +
                             "v 2 0 0\nv 3 0 0\nv 4 0 0\n"
                             "f 5 6 7\n"      // collinear
                             "f 1 1 2\n"      // a repeated vertex leaves two
                             "f 1 2 2 3\n");  // a repeated vertex leaves a real triangle
    const Scene s = mesh(m, 10.0);
    EXPECT_EQ(s.stats.input_faces, 4u);
    EXPECT_EQ(s.stats.dropped_degenerate, 2u);
    ASSERT_EQ(s.size(), 2u);
    EXPECT_EQ(s.patches[1].count, 3u);
    EXPECT_EQ(s.patches[1].area, 0.5);
}

TEST(Mesher, AllDegenerateIsRefused) {
    const ObjModel m = parse("v 0 0 0\nv 1 0 0\nv 2 0 0\nf 1 2 3\n");
    try {
        mesh(m, 1.0);
        FAIL() << "no error";
    } catch (const InputError& e) {
        EXPECT_NE(std::string(e.what()).find("t.obj: no faces with non-zero area"), std::string::npos) << e.what();
    }
    EXPECT_EQ(count_patches(m, 1.0), 0u);
}

TEST(Mesher, InvalidEdgeBoundIsRefused) {
    const ObjModel m = parse(kUnitSquare);
    for (const double L : {-1.0, std::nan(""), std::numeric_limits<double>::infinity()}) {
        EXPECT_THROW(mesh(m, L), InputError) << L;
        EXPECT_THROW(count_patches(m, L), InputError) << L;
    }
}

TEST(Mesher, AbsurdMeshIsRefusedBeforeAllocating) {
    const ObjModel m = parse(kUnitSquare);
    // 1e-9 on a unit square: 1e9 divisions per side, 1e18 patches. Were anything allocated first,
    // this test would die of memory instead of catching the error.
    EXPECT_NEAR(static_cast<double>(count_patches(m, 1e-9)), 1e18, 1e18 * 1e-8);
    try {
        mesh(m, 1e-9);
        FAIL() << "no error";
    } catch (const InputError& e) {
        const std::string msg = e.what();
        EXPECT_NE(msg.find("t.obj: --max-patch-edge 1e-09 would make about 1e+18 patches"), std::string::npos) << msg;
        EXPECT_NE(msg.find("the limit is 50000000 patches"), std::string::npos) << msg;
    }
    // Beyond 2^64: the count saturates instead of wrapping.
    EXPECT_EQ(count_patches(m, 1e-12), std::numeric_limits<std::size_t>::max());
    // A small limit refuses a small mesh the same way.
    MeshOptions o;
    o.max_patch_edge = 0.25;
    o.max_patches = 15;
    EXPECT_THROW(build_scene(m, o), InputError);
    o.max_patches = 16;
    EXPECT_EQ(build_scene(m, o).size(), 16u);
}

TEST(Mesher, TargetPatchCountOnTheCornellBox) {
    const ObjModel m = load_cornell_box();
    for (const std::size_t target : {200u, 2000u, 5000u, 20000u}) {
        MeshOptions o;
        o.target_patches = target;
        const Scene s = build_scene(m, o);
        const double ratio = static_cast<double>(s.size()) / static_cast<double>(target);
        EXPECT_GT(ratio, 0.7) << target;
        EXPECT_LT(ratio, 1.3) << target;
        EXPECT_EQ(s.size(), count_patches(m, s.stats.max_patch_edge));
        EXPECT_EQ(s.stats.how.rfind(fmt::format("--patches {} -> --max-patch-edge ", target), 0), 0u) << s.stats.how;
        expect_edges_within(s, s.stats.max_patch_edge, 560.0);  // coordinates up to 556 mm
        // The printed edge reproduces the same mesh.
        const std::string printed = s.stats.how.substr(s.stats.how.find("--max-patch-edge ") + 17);
        const Scene again = mesh(m, std::stod(printed));
        EXPECT_EQ(again.fingerprint, s.fingerprint) << s.stats.how;
    }
    const Scene d = build_scene(m, MeshOptions{});
    EXPECT_EQ(d.stats.how.rfind("default: --patches 2000 -> --max-patch-edge ", 0), 0u) << d.stats.how;
    EXPECT_NEAR(static_cast<double>(d.size()), 2000.0, 600.0);
}

TEST(Mesher, TargetBelowTheFaceCountGivesOnePatchPerPiece) {
    const ObjModel m = load_obj(kExamples / "cube.obj");
    MeshOptions o;
    o.target_patches = 3;
    const Scene s = build_scene(m, o);
    EXPECT_EQ(s.size(), 6u);
    EXPECT_EQ(s.stats.max_patch_edge, 1.0);
}

// Scene::grids describes each piece so that a renderer can draw it whole and find the patch of a
// point: check the documented cell → patch numbering against the patches' own vertices.
TEST(Mesher, GridsDescribeEveryPatch) {
    ObjModel m = load_cornell_box();
    const Scene s = build_scene(m, MeshOptions{});
    std::uint32_t next = 0;
    std::size_t triangle_grids = 0;
    for (const PatchGrid& g : s.grids) {
        ASSERT_EQ(g.first_patch, next) << "grids cover the patches in order";
        const auto& c = g.corners;
        if (g.count == 4) {
            const auto at = [&](std::uint32_t i, std::uint32_t j) {
                const double u = static_cast<double>(i) / g.nu, v = static_cast<double>(j) / g.nv;
                return (1 - u) * (1 - v) * c[0] + u * (1 - v) * c[1] + u * v * c[2] + (1 - u) * v * c[3];
            };
            for (std::uint32_t j = 0; j < g.nv; ++j)
                for (std::uint32_t i = 0; i < g.nu; ++i) {
                    const auto pv = s.patch_vertices(g.first_patch + j * g.nu + i);
                    // The same formula in the same order: bit-identical.
                    EXPECT_EQ(pv[0], at(i, j));
                    EXPECT_EQ(pv[2], at(i + 1, j + 1));
                }
            next += g.nu * g.nv;
        } else {
            ++triangle_grids;
            const std::uint32_t k = g.nu;
            ASSERT_EQ(g.nv, k);
            EXPECT_EQ(c[3], c[2]);
            // Upright cell (i, j) starts at vertex c0 + i/k (c1 − c0) + j/k (c2 − c0); within
            // rounding of coordinates up to 560 mm (a few eps × 560 ≈ 1e-12).
            const auto at = [&](std::uint32_t i, std::uint32_t j) {
                return c[0] + (static_cast<double>(i) / k) * (c[1] - c[0]) + (static_cast<double>(j) / k) * (c[2] - c[0]);
            };
            for (std::uint32_t j = 0; j < k; ++j)
                for (std::uint32_t i = 0; i + j < k; ++i) {
                    const std::uint32_t up = g.first_patch + j * (2 * k - j) + 2 * i;
                    EXPECT_LT(glm::length(s.patch_vertices(up)[0] - at(i, j)), 1e-12);
                    if (i + j + 1 < k) {
                        EXPECT_LT(glm::length(s.patch_vertices(up + 1)[1] - at(i + 1, j + 1)), 1e-12);
                    }
                }
            next += k * k;
        }
    }
    EXPECT_EQ(next, s.size());
    EXPECT_EQ(triangle_grids, 2u);  // the non-planar left wall
}

TEST(Mesher, FingerprintIsStableAndFollowsGeometry) {
    const fs::path cube = kExamples / "cube.obj";
    const std::uint64_t a = mesh(load_obj(cube), 0.3).fingerprint;
    EXPECT_EQ(a, mesh(load_obj(cube), 0.3).fingerprint);
    EXPECT_NE(a, mesh(load_obj(cube), 0.2).fingerprint);  // 0.25 gives the same 4 × 4 grid as 0.3

    const std::string square = "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf 1 2 3 4\n";
    const std::uint64_t b = mesh(parse(square), 0.5).fingerprint;
    EXPECT_NE(b, mesh(parse("v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1.0000001 0\nf 1 2 3 4\n"), 0.5).fingerprint);
    // The same two triangles in one object, then in two.
    const std::string tris = "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\no a\nf 1 2 3\n";
    EXPECT_NE(mesh(parse(tris + "f 1 3 4\n"), 0.5).fingerprint, mesh(parse(tris + "o b\nf 1 3 4\n"), 0.5).fingerprint);
    // Materials do not enter it: a matrix stays valid when only Kd/Ke change.
    const MtlResolver red = [](const std::string&) { return std::optional<std::string>("newmtl m\nKd 0.9 0 0\n"); };
    EXPECT_EQ(b, mesh(parse_obj("mtllib m.mtl\nusemtl m\n" + square, "t.obj", red), 0.5).fingerprint);
}

}  // namespace
