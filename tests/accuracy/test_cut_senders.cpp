// Senders cut by a receiver's plane (docs/accuracy.md, "Senders cut by a receiver's plane"): the
// L-shaped room's case. A wall in y = 0 runs past the plane x = 1 of a receiver wall that faces
// back towards x < 0; the sender patches that straddle x = 1 see the receiver from their part at
// x < 1 only, and their centre (where a hemicube stands) lies behind it or grazes it. Their
// entries must be the closed-form value of the sender clipped to the receiver's front, where the
// plane test can prove the pair unoccluded, and must be left alone where it cannot.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <vector>

#include "ffcube/accuracy/near_field.hpp"
#include "ffcube/geometry/analytic.hpp"
#include "support/scenes.hpp"

namespace ffcube {
namespace {

// The sender wall (y = 0, normal +y, x from 0 to 2.3) in 8 columns of 0.2875: the fourth spans
// x = 0.8625..1.15, its centre at 1.006, just behind the receiver's plane x = 1. The receiver
// (x = 1, normal −x, y from 1 to 2) faces the part of the sender at x < 1.
std::vector<NamedPolygon> cut_sender_scene() {
    return {
        {"sender", {{0, 0, 0}, {0, 0, 1}, {2.3, 0, 1}, {2.3, 0, 0}}},
        {"receiver", {{1, 1, 0}, {1, 1, 1}, {1, 2, 1}, {1, 2, 0}}},
    };
}

bool cut_by_x1(const Scene& s, std::uint32_t i) {
    bool before = false, after = false;
    for (const Vec3& v : s.patch_vertices(i)) {
        before = before || v.x < 1 - 1e-9;
        after = after || v.x > 1 + 1e-9;
    }
    return before && after;
}

// The hemicube's options (sender quadrature) with the far field on, or `auto` and off for its
// cost: a budget of 1 µs a row is above the least a row can cost (8 ns a patch, 48 patches) but
// below the estimate (tens of far entries at about 250 ns each), so the planes are made and stay
// for the cut senders.
NearFieldOptions hemicube_options(bool far_on) {
    NearFieldOptions o;
    o.sender_quadrature = true;
    o.far_field = far_on ? NearFieldOptions::FarField::on : NearFieldOptions::FarField::automatic;
    o.far_field_budget_ns = 1000;
    o.far_field_row_ns = 0;
    return o;
}

TEST(CutSenders, EntriesAreTheClippedSendersClosedForm) {
    const Scene s = test::make_scene(cut_sender_scene(), 0.3);
    for (const bool far_on : {false, true}) {
        const NearFieldCorrector c(s, hemicube_options(far_on));
        ASSERT_EQ(c.far_field_planes() > 0, far_on) << c.far_field_status();
        std::size_t cut_rows = 0, checked = 0;
        for (std::uint32_t i = 0; i < s.size(); ++i) {
            if (s.patches[i].object != 0 || !cut_by_x1(s, i)) continue;
            ++cut_rows;
            NearAnalysis a;
            c.analyse(i, a);
            EXPECT_GT(a.cut_sender_entries, 0u) << i;
            EXPECT_EQ(a.cut_sender_unproven, 0u) << i;  // nothing stands between the walls
            for (const auto& [j, f] : a.exact) {
                // ff_polygon_polygon clips each polygon to the other's front (its contour integral:
                // ~1e-12 relative); the correction's values are that or the 6 × 6 rule on the
                // clipped patches, whose worst relative error is 3.6e-10 (near_values.hpp): 1e-9.
                const double ref = ff_polygon_polygon(s.patch_vertices(i), s.patch_vertices(j));
                EXPECT_NEAR(f, ref, 1e-9 * ref + 1e-15) << i << " " << j << (far_on ? " far on" : " far off");
                ++checked;
            }
            // Without the clip the centre, behind x = 1, would see nothing of the receiver: the
            // row's receiver entries carry a real share (the part at x < 1 is 0.1375 of 0.2875).
            double to_receiver = 0;
            for (const auto& [j, f] : a.exact) to_receiver += s.patches[j].object == 1 ? f : 0.0;
            EXPECT_GT(to_receiver, 1e-3) << i;
        }
        EXPECT_GT(cut_rows, 0u);
        EXPECT_GT(checked, 0u);
    }
}

// A two-sided plate at y = 0.5 across x = 0.8..1.2 hides the receiver from the cut column's front
// part: those pairs are not proven and keep their measured values.
TEST(CutSenders, AnOccluderBetweenLeavesThePairAlone) {
    std::vector<NamedPolygon> polys = cut_sender_scene();
    polys.push_back({"plate_a", {{0.8, 0.5, 0}, {1.2, 0.5, 0}, {1.2, 0.5, 1}, {0.8, 0.5, 1}}});
    polys.push_back({"plate_b", {{0.8, 0.5, 0}, {0.8, 0.5, 1}, {1.2, 0.5, 1}, {1.2, 0.5, 0}}});
    const Scene s = test::make_scene(polys, 0.3);
    const NearFieldCorrector c(s, hemicube_options(false));
    ASSERT_EQ(c.far_field_planes(), 0u) << c.far_field_status();
    std::size_t cut_rows = 0;
    for (std::uint32_t i = 0; i < s.size(); ++i) {
        if (s.patches[i].object != 0 || !cut_by_x1(s, i)) continue;
        ++cut_rows;
        NearAnalysis a;
        c.analyse(i, a);
        EXPECT_GT(a.cut_sender_unproven, 0u) << i;
        for (const auto& [j, f] : a.exact) EXPECT_NE(s.patches[j].object, 1u) << i << " " << j;
    }
    EXPECT_GT(cut_rows, 0u);
}

}  // namespace
}  // namespace ffcube
