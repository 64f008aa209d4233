// Sky view factors from a matrix set by hand: SVF_i = 1 − Σ_j F_ij, object values area-weighted.
#include <gtest/gtest.h>

#include "ffcube/formfactor/sky.hpp"
#include "support/scenes.hpp"

namespace ffcube {
namespace {

TEST(Sky, OneMinusTheRowSumPerPatchAndAreaWeightedPerObject) {
    // Patches 0 and 1 (unit squares, objects a and b), patch 2 (2 × 2, object c).
    const Scene s = test::make_scene({test::square_z("a", 0, true), test::square_z("b", 1, false, 1.0, Vec3(0, 0, 0)),
                                      test::square_z("c", 3, false, 2.0)},
                                     10.0);
    ASSERT_EQ(s.size(), 3u);
    CsrMatrix F(3);
    F.append_row(SparseRow{{1, 2}, {0.5, 0.25}});  // sees 0.75: SVF 0.25
    F.append_row(SparseRow{{}, {}});               // sees nothing: SVF 1
    F.append_row(SparseRow{{0, 1}, {0.75, 0.5}});  // sums to 1.25 (rounding gone wild): clamped at 0
    const std::vector<double> svf = sky_view_factors(F);
    ASSERT_EQ(svf.size(), 3u);
    EXPECT_NEAR(svf[0], 0.25, 1e-7);  // float entries: 2^-24 relative
    EXPECT_EQ(svf[1], 1.0);
    EXPECT_EQ(svf[2], 0.0);
    const SkyStats st = sky_stats(svf, s);
    EXPECT_NEAR(st.min, 0.0, 0.0);
    EXPECT_NEAR(st.max, 1.0, 0.0);
    EXPECT_NEAR(st.mean, 1.25 / 3.0, 1e-7);
    EXPECT_NEAR(st.area_weighted_mean, (0.25 + 1.0 + 0.0) / 6.0, 1e-7);  // areas 1, 1, 4
    const std::vector<double> area = object_areas(s);
    EXPECT_DOUBLE_EQ(area[2], 4.0);
    // Each object is one patch here, so the object means are the patch values.
    const std::vector<double> per_object = object_means(svf, s);
    EXPECT_NEAR(per_object[0], 0.25, 1e-7);
    EXPECT_EQ(per_object[1], 1.0);
}

TEST(Sky, ObjectValueIsTheAreaWeightedMeanOfItsPatches) {
    // One 2 × 2 square meshed into four unit patches, all of object "a".
    const Scene s = test::make_scene({test::square_z("a", 0, true, 2.0)}, 1.0);
    ASSERT_EQ(s.size(), 4u);
    const std::vector<double> v = {0.1, 0.2, 0.3, 0.6};
    EXPECT_NEAR(object_means(v, s)[0], 0.3, 1e-12);  // equal areas: the plain mean
}

}  // namespace
}  // namespace ffcube
