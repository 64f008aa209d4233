// What pictures and meshes of a solved scene show: radiance B/π, the exposure, the PLY colours.
#include <gtest/gtest.h>

#include <numbers>

#include "ffcube/render/image.hpp"
#include "ffcube/render/solved_scene.hpp"
#include "support/scenes.hpp"

namespace ffcube {
namespace {

TEST(SolvedScene, RadianceExposureAndPlyColours) {
    const Scene scene = test::make_scene({test::square_z("a", 0, true), test::square_z("b", 1, false, 2.0)}, 0.5);
    std::vector<Vec3> B(scene.size());
    for (std::size_t i = 0; i < B.size(); ++i) {
        const double x = static_cast<double>(i);
        B[i] = Vec3(1.0 + x, 2.0, 0.5 * x);
    }
    const std::vector<Vec3> L = patch_radiance(B);
    ASSERT_EQ(L.size(), B.size());
    for (std::size_t i = 0; i < B.size(); ++i) EXPECT_DOUBLE_EQ(L[i].r * std::numbers::pi, B[i].r);

    EXPECT_EQ(scene_exposure(scene, L, 0.25), 0.25);
    // Automatic: auto_exposure of the luminances weighted by area, computed independently here.
    std::vector<double> lum, area;
    for (std::size_t i = 0; i < L.size(); ++i) {
        lum.push_back(0.2126 * L[i].r + 0.7152 * L[i].g + 0.0722 * L[i].b);
        area.push_back(scene.patches[i].area);
    }
    const double automatic = scene_exposure(scene, L, std::nullopt);
    EXPECT_DOUBLE_EQ(automatic, auto_exposure(lum, area));
    EXPECT_GT(automatic, 0.0);

    // Flat shading: every corner carries its patch's B; its colour is sRGB of exposure × B/π.
    const PlyMesh ply = solved_ply_mesh(scene, B, Shading::Flat, automatic);
    ASSERT_EQ(ply.values.size(), ply.positions.size());
    ASSERT_EQ(ply.colors.size(), ply.positions.size());
    std::size_t corner = 0;
    for (std::size_t f = 0; f < ply.face_sizes.size(); ++f)
        for (std::uint32_t k = 0; k < ply.face_sizes[f]; ++k, ++corner) {
            const Vec3 b = ply.values[ply.face_indices[corner]];
            const auto& c = ply.colors[ply.face_indices[corner]];
            EXPECT_EQ(c[0], encode_srgb8(b.r / std::numbers::pi, automatic));
            EXPECT_EQ(c[2], encode_srgb8(b.b / std::numbers::pi, automatic));
        }
    EXPECT_EQ(corner, ply.face_indices.size());
}

}  // namespace
}  // namespace ffcube
