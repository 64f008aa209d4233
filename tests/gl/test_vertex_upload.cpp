// Vertex data uploaded once (HemicubeOptions::VertexUpload::once, shaders/item.vert's
// WORLD_POSITIONS): the world positions go to the GL once as doubles and the vertex shader makes
// each hemicube's eye-relative floats itself, `precise`, in the CPU's order. The CPU still makes
// the same floats for culling, so the two must agree to the bit, or a piece culled as off a face
// could have drawn a pixel there. Compared here row by row, bit for bit, against the floats
// uploaded every hemicube, on scenes where rounding has room to differ: far-off coordinates
// (1e5 from the origin), every kind of piece (triangles split into similar triangles, general
// quads, parallelograms, T-vertices), sizes over three decades, sub-hemicubes at other eyes.
// What this can see: a shader that loses precision (world positions as floats: 4e-3 off at
// 1e5, which moves pixels; checked to fail). An ulp's difference in a vertex (the sums in
// another order) moves no pixel here, since the rasterizer snaps vertices to 1/256 of a pixel:
// that the floats are the same bits rests on the shader doing the CPU's operations, `precise`.
#include <gtest/gtest.h>

#include <vector>

#include "ffcube/gl/hemicube_provider.hpp"
#include "support/planned_rows.hpp"
#include "support/scenes.hpp"

namespace ffcube {
namespace {

std::vector<SparseRow> compute(const Scene& s, HemicubeOptions::VertexUpload upload, RowProvider::RowPlan plan) {
    HemicubeOptions o;
    o.resolution = 64;
    o.threads = 2;
    o.vertex_upload = upload;
    return test::all_rows(s, o, plan).rows;
}

// An open room (floor, three walls) with a trapezoid (a general quad), a tilted triangle, a
// thin sliver and a small parallelogram in it, and a wall split so that its neighbour has a
// T-vertex; all moved by `offset`.
Scene mixed_room(const Vec3& offset) {
    const auto at = [&](double x, double y, double z) { return offset + Vec3(x, y, z); };
    std::vector<NamedPolygon> polys{
        {"floor", {at(0, 0, 0), at(4, 0, 0), at(4, 4, 0), at(0, 4, 0)}},
        {"wall", {at(0, 0, 0), at(0, 4, 0), at(0, 4, 3), at(0, 0, 3)}},
        {"wall", {at(4, 0, 0), at(4, 0, 1.5), at(4, 4, 1.5), at(4, 4, 0)}},
        {"wall", {at(4, 0, 1.5), at(4, 0, 3), at(4, 4, 3), at(4, 4, 1.5)}},
        {"back", {at(0, 4, 0), at(4, 4, 0), at(4, 4, 3), at(0, 4, 3)}},
        {"trapezoid", {at(1, 1, 1), at(3, 1, 1), at(2.5, 2.5, 1.4), at(1.4, 2.5, 1.4)}},
        {"triangle", {at(2.6, 0.4, 0.3), at(3.6, 0.9, 0.5), at(3.0, 1.8, 2.2)}},
        {"sliver", {at(0.5, 3.0, 0.2), at(3.5, 3.01, 0.25), at(0.5, 3.02, 0.3)}},
        {"chip", {at(0.3, 0.3, 2.0), at(0.33, 0.3, 2.0), at(0.35, 0.33, 2.01), at(0.32, 0.33, 2.01)}},
    };
    return test::make_scene(polys, 0.5);
}

void expect_same(const Scene& s, RowProvider::RowPlan plan) {
    const std::vector<SparseRow> per = compute(s, HemicubeOptions::VertexUpload::per_hemicube, plan);
    const std::vector<SparseRow> once = compute(s, HemicubeOptions::VertexUpload::once, plan);
    std::size_t nonzero = 0;
    for (std::uint32_t i = 0; i < s.size(); ++i) {
        ASSERT_EQ(per[i].col, once[i].col) << "row " << i;
        ASSERT_EQ(per[i].val, once[i].val) << "row " << i;
        nonzero += per[i].col.size();
    }
    EXPECT_GT(nonzero, 5 * s.size());  // the rows see the room, not nothing
}

TEST(VertexUpload, OnceIsThePerHemicubeFloatsBitForBit) {
    const Scene near = mixed_room(Vec3(0.0));
    ASSERT_GT(near.size(), 200u);
    expect_same(near, RowProvider::RowPlan::centre);
}

TEST(VertexUpload, FarOffCoordinatesAndSubHemicubesToo) {
    // 1e5 from the origin: a float of the world position would be off by 4e-3, a tenth of the
    // chip; the eye-relative floats are exact to their own size either way.
    const Scene far = mixed_room(Vec3(1e5, -2e5, 3e4));
    expect_same(far, RowProvider::RowPlan::centre);
    expect_same(far, RowProvider::RowPlan::sampled);
}

}  // namespace
}  // namespace ffcube
