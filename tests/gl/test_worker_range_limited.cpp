// Range-limited sub-hemicubes (HemicubeOptions::sub_hemicube_range; docs/accuracy.md,
// "Range-limited sub-hemicubes"): a row of sub-hemicubes on a scene of many pieces draws at its
// quadrature points only the pieces within R of the sender, and one full hemicube at the centroid
// of the rest. Entries wholly within range are the plain sub-hemicube row's, bit for bit; a far
// receiver behind a near occluder gets the shadowed value; off (and auto below the piece
// threshold) is the plain row, bit for bit.
#include <gtest/gtest.h>

#include <glm/common.hpp>
#include <glm/geometric.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <map>
#include <numbers>
#include <string>
#include <vector>

#include "ffcube/geometry/analytic.hpp"
#include "ffcube/gl/hemicube_provider.hpp"
#include "ffcube/hemicube/layout.hpp"
#include "support/scenes.hpp"
#include "support/rows.hpp"

namespace ffcube {
namespace {

using Plan = RowProvider::RowPlan;

std::map<std::uint32_t, SparseRow> rows_of(const Scene& scene, HemicubeOptions o, const std::vector<std::uint32_t>& rows,
                                           const std::vector<Plan>& plans, HemicubeStats* stats = nullptr) {
    HemicubeRowProvider provider(scene, o);
    std::map<std::uint32_t, SparseRow> out;
    provider.compute_rows_planned(rows, plans, [&](std::uint32_t i, const SparseRow& r) { out[i] = r; });
    if (stats) *stats = provider.stats();
    return out;
}

using test::entry;

// A unit square sender on the ground (z = 0, facing up), a unit square occluder 2 above it
// (facing down: near, within R = 24 sizes), and a plate 8000 wide 40 above (facing down: wholly
// beyond R, so no sub-hemicube draws it). The plate's factor past the occluder is
// F(sender → plate) − F(sender → occluder) exactly: every ray from the sender through the
// occluder meets the plate (it reaches z = 40 within |x|, |y| ≤ 0.5 + 20 < 4000).
struct Shadow {
    Scene scene;
    std::uint32_t sender = 0, occluder = 0, plate = 0;
    static constexpr double L = 4000, H = 40;
    Shadow() {
        const std::vector<NamedPolygon> polys{
            {"sender", {{-0.5, -0.5, 0}, {0.5, -0.5, 0}, {0.5, 0.5, 0}, {-0.5, 0.5, 0}}},
            {"occluder", {{-0.5, -0.5, 2}, {-0.5, 0.5, 2}, {0.5, 0.5, 2}, {0.5, -0.5, 2}}},
            {"plate", {{-L, -L, H}, {-L, L, H}, {L, L, H}, {L, -L, H}}},
        };
        scene = test::make_scene(polys, 1e9);
        for (std::uint32_t p = 0; p < scene.size(); ++p) {
            const std::uint32_t o = scene.patches[p].object;
            (o == 0 ? sender : o == 1 ? occluder : plate) = p;
        }
    }
};

// The plate's entry against the closed forms, and against the plain 4 × 4 row:
//  - the occluder's entry is the plain row's, bit for bit (near: the same pixels, summed alike);
//  - the plate's entry, both ways, sums ΔF over the same half-resolution directions that see
//    past the occluder (the centroid's 4 full pixels of a half pixel add up to its ΔF exactly),
//    except where the plate's outline is: at elevations below atan(40/4000) = 0.57°, inside the
//    bottom row of the half-resolution side tiles (1/16 of their height, 3.6°). So they differ by
//    at most that row's ΔF;
//  - against the closed form F(plate) − F(occluder): the occluder's outline in each
//    half-resolution sub-hemicube (n = 64; its image on the top face is 16 pixels square, an
//    outline of 64 pixels, 4n as a bound) is wrongly in or out by at most ΔF_max = 4/(π n²) per
//    pixel, uniform in ±½: σ ≤ √(4n) ΔF_max/√12 per point, √(Σ w²) = 1/4 of it for the 16
//    equal-weight points; asserted within 4σ plus the horizon row above.
TEST(RangeLimitedSubHemicubes, FarReceiverBehindANearOccluderGetsTheShadowedValue) {
    const Shadow s;
    HemicubeOptions o;
    o.resolution = 128;
    o.threads = 1;
    o.sub_hemicube_range = HemicubeOptions::SubHemicubeRange::automatic;
    o.sub_hemicube_range_min_pieces = 1;  // three pieces: the rule asked for explicitly
    o.sub_hemicube_range_max_share = 1;
    HemicubeStats st;
    const std::vector<std::uint32_t> rows{s.sender};
    const std::vector<Plan> plans{Plan::sampled_fine};
    const SparseRow on = rows_of(s.scene, o, rows, plans, &st).at(s.sender);
    EXPECT_EQ(st.range_limited_rows, 1u);
    EXPECT_GT(st.pieces_out_of_range, 0u) << "the plate is drawn by no sub-hemicube";
    o.sub_hemicube_range = HemicubeOptions::SubHemicubeRange::off;
    HemicubeStats st_off;
    const SparseRow off = rows_of(s.scene, o, rows, plans, &st_off).at(s.sender);
    EXPECT_EQ(st_off.range_limited_rows, 0u);

    EXPECT_EQ(entry(on, s.occluder), entry(off, s.occluder));

    const HemicubeLayout half(64);
    double horizon = 0;
    for (const FaceSpec& f : half.faces()) {
        if (f.face == HemicubeFace::Top) continue;
        for (int x = f.viewport.x; x < f.viewport.x + f.viewport.width; ++x)
            horizon += half.delta_ff()[static_cast<std::size_t>(f.viewport.y) * half.atlas_width() + x];
    }
    EXPECT_NEAR(entry(on, s.plate), entry(off, s.plate), horizon);

    const double f_plate = ff_parallel_rectangles_offset(-0.5, 0.5, -0.5, 0.5, -Shadow::L, Shadow::L, -Shadow::L,
                                                         Shadow::L, Shadow::H);
    const double f_occ = ff_parallel_rectangles(1, 1, 2);
    const double shadowed = f_plate - f_occ;
    const double n = 64, sigma = std::sqrt(4 * n) * 4 / (std::numbers::pi * n * n) / std::sqrt(12.0) / 4;
    EXPECT_NEAR(entry(on, s.plate), shadowed, 4 * sigma + horizon);
    EXPECT_NEAR(entry(on, s.occluder), f_occ, 4 * sigma);
    std::printf("plate: closed form %.6f, range-limited %.6f, plain %.6f (4 sigma %.1e, horizon row %.1e)\n", shadowed,
                entry(on, s.plate), entry(off, s.plate), 4 * sigma, horizon);
}

// A 15 × 15 grid of unit boxes (five faces each, 1 to 4 tall) on a 50 × 50 ground of unit cells,
// every face and cell its own piece (3,400, above the default threshold of 1,000). Rows of ground
// cells and of box walls, at 4 × 4 and 2 × 2 points:
//  - every entry of a near piece (its box wholly within R − r of the centroid, the worker's
//    rule computed here from the polygon) is the plain row's, bit for bit;
//  - the sum of the other (far) entries differs from the plain row's only in directions where,
//    from some eye, what is not near meets the sky (elsewhere both count the same
//    half-resolution directions, as in the test above). A piece that is not near reaches beyond
//    R − r, so none of it is nearer than R − r − D (D its diameter, at most √17 here), and from
//    the centroid such a direction lies within the parallax p = r/(R − r − D) of the centroid's
//    own sky line. A half-resolution pixel (n = 64) spans at least (2/n)/3 rad (at a corner of a
//    face, distance √3 and foreshortened), so p is within ⌈3pn/2⌉ pixels, plus one of
//    quantisation: the sums differ by at most the ΔF of the half-resolution pixels within that
//    many pixels (same tile) of a half pixel whose 4 full pixels in the centroid's hemicube show
//    both sky and a piece that is not near.
struct Aabb {
    Vec3 lo, hi;
};
struct BoxGrid {
    Scene scene;
    std::vector<Aabb> object_box;
    static constexpr double kDiameter = 4.2;  // the largest piece: a 1 × 4 wall, √17 = 4.12
    BoxGrid() {
        std::vector<NamedPolygon> all;
        auto box_at = [](int x) { return x >= -22 && x <= 20 && (x + 22) % 3 == 0; };
        for (int x = -25; x < 25; ++x)
            for (int y = -25; y < 25; ++y) {
                if (box_at(x) && box_at(y)) continue;  // under a box
                all.push_back({"cell" + std::to_string(x) + "_" + std::to_string(y),
                                 {{x, y, 0.0}, {x + 1.0, y, 0.0}, {x + 1.0, y + 1.0, 0.0}, {x, y + 1.0, 0.0}}});
            }
        for (int a = 0; a < 15; ++a)
            for (int b = 0; b < 15; ++b) {
                const std::string name = "box" + std::to_string(a) + "_" + std::to_string(b);
                const double x0 = -22 + 3 * a, y0 = -22 + 3 * b, x1 = x0 + 1, y1 = y0 + 1, z1 = 1 + (a * 7 + b * 3) % 4;
                all.push_back({name + "w", {{x0, y0, 0}, {x0, y0, z1}, {x0, y1, z1}, {x0, y1, 0}}});
                all.push_back({name + "e", {{x1, y0, 0}, {x1, y1, 0}, {x1, y1, z1}, {x1, y0, z1}}});
                all.push_back({name + "s", {{x0, y0, 0}, {x1, y0, 0}, {x1, y0, z1}, {x0, y0, z1}}});
                all.push_back({name + "n", {{x0, y1, 0}, {x0, y1, z1}, {x1, y1, z1}, {x1, y1, 0}}});
                all.push_back({name + "t", {{x0, y0, z1}, {x1, y0, z1}, {x1, y1, z1}, {x0, y1, z1}}});
            }
        for (const auto& p : all) {
            Aabb b{p.vertices[0], p.vertices[0]};
            for (const Vec3& v : p.vertices) {
                b.lo = glm::min(b.lo, v);
                b.hi = glm::max(b.hi, v);
            }
            object_box.push_back(b);
        }
        scene = test::make_scene(all, 1.5);
        polys = all;
    }
    std::vector<NamedPolygon> polys;
};

TEST(RangeLimitedSubHemicubes, NearEntriesExactFarSumWithinTheSkyLineBound) {
    const BoxGrid g;
    ASSERT_GE(g.scene.grids.size(), 1000u);
    std::vector<std::uint32_t> rows;
    std::vector<Plan> plans;
    for (std::uint32_t p = 0; p < g.scene.size(); p += 151) {
        rows.push_back(p);
        plans.push_back(rows.size() % 2 ? Plan::sampled_fine : Plan::sampled);
    }
    HemicubeOptions o;
    o.resolution = 128;
    o.threads = 2;
    o.sub_hemicube_range = HemicubeOptions::SubHemicubeRange::automatic;
    o.rotate = false;  // the centroid's view of what is not near (below) is drawn in another scene
    o.sub_hemicube_range_max_share = 1;  // every row, though most of the grid lies within range
    HemicubeStats st;
    const auto on = rows_of(g.scene, o, rows, plans, &st);
    o.sub_hemicube_range = HemicubeOptions::SubHemicubeRange::off;
    const auto off = rows_of(g.scene, o, rows, plans);
    o.threads = 1;
    // Ground cells beside a box are not cut by it: no row takes the exposed-part rule.
    EXPECT_EQ(st.partly_enclosed_rows, 0u);
    EXPECT_EQ(st.range_limited_rows, rows.size());

    const HemicubeLayout full(128), half(64);
    std::size_t near_checked = 0;
    for (std::uint32_t p : rows) {
        const Patch& pa = g.scene.patches[p];
        const auto v = g.scene.patch_vertices(p);
        double r = 0;
        for (std::size_t k = 0; k < pa.count; ++k) r = std::max(r, glm::length(v[k] - pa.centroid));
        r += HemicubeRowProvider::kEyeOffset * pa.size;
        const double near_range = o.sub_hemicube_range_k * pa.size * (1 - 1e-9) - r;
        const double parallax = r / (near_range - BoxGrid::kDiameter);
        const int reach = static_cast<int>(std::ceil(3 * parallax * 64 / 2)) + 1;
        auto is_near = [&](std::uint32_t j) {
            const Aabb& b = g.object_box[g.scene.patches[j].object];
            const Vec3 d = glm::max(glm::abs(b.lo - pa.centroid), glm::abs(b.hi - pa.centroid));
            return glm::length(d) <= near_range;
        };
        const SparseRow& a = on.at(p);
        const SparseRow& b = off.at(p);
        double far_a = 0, far_b = 0;
        for (std::size_t k = 0; k < a.col.size(); ++k) {
            if (is_near(a.col[k])) {
                EXPECT_EQ(a.val[k], entry(b, a.col[k])) << "row " << p << " entry " << a.col[k];
                ++near_checked;
            } else {
                far_a += a.val[k];
            }
        }
        for (std::size_t k = 0; k < b.col.size(); ++k) {
            if (is_near(b.col[k]))
                EXPECT_NE(entry(a, b.col[k]), 0.0) << "row " << p << " lost near entry " << b.col[k];
            else
                far_b += b.val[k];
        }
        // The sky-line bound from the centroid's hemicube of what is not near: a scene of those
        // pieces and the sender's polygon (meshed into the same patches; found by its centroid).
        std::vector<NamedPolygon> far_polys;
        for (std::size_t k = 0; k < g.polys.size(); ++k) {
            bool keep = k == pa.object;
            if (!keep) {
                const Aabb& bk = g.object_box[k];
                keep = !(glm::length(glm::max(glm::abs(bk.lo - pa.centroid), glm::abs(bk.hi - pa.centroid))) <= near_range);
            }
            if (keep) far_polys.push_back(g.polys[k]);
        }
        const Scene far_scene = test::make_scene(far_polys, 1.5);
        std::uint32_t p_far = 0;
        while (p_far < far_scene.size() && glm::length(far_scene.patches[p_far].centroid - pa.centroid) > 1e-12) ++p_far;
        ASSERT_LT(p_far, far_scene.size());
        HemicubeRowProvider far_view(far_scene, o);
        const auto ids = far_view.item_buffer(p_far);
        const int W = full.atlas_width(), HW = half.atlas_width();
        std::vector<std::uint8_t> cls(static_cast<std::size_t>(HW) * half.atlas_height(), 0);  // bit 0 sky, bit 1 far
        for (int y = 0; y < full.atlas_height(); ++y)
            for (int x = 0; x < W; ++x) {
                const std::uint32_t id = ids[static_cast<std::size_t>(y) * W + x];
                auto& c = cls[static_cast<std::size_t>(y / 2) * HW + x / 2];
                if (id == 0) c |= 1;
                else if (id != 0xFFFFFFFFu) c |= 2;
            }
        double bound = 0;
        for (const FaceSpec& f : half.faces()) {
            const auto& vp = f.viewport;
            for (int y = vp.y; y < vp.y + vp.height; ++y)
                for (int x = vp.x; x < vp.x + vp.width; ++x) {
                    std::uint8_t c = 0;
                    for (int yy = std::max(vp.y, y - reach); yy <= std::min(vp.y + vp.height - 1, y + reach); ++yy)
                        for (int xx = std::max(vp.x, x - reach); xx <= std::min(vp.x + vp.width - 1, x + reach); ++xx)
                            c |= cls[static_cast<std::size_t>(yy) * HW + xx];
                    if (c == 3) bound += half.delta_ff()[static_cast<std::size_t>(y) * HW + x];
                }
        }
        // Plus one row of half-resolution pixels at the horizon: a far piece seen edge-on there can
        // be thinner than a full pixel from the centroid (no pixel centre of it) and still cover
        // a sub-hemicube's pixel centre.
        double horizon = 0;
        for (const FaceSpec& f : half.faces())
            if (f.face != HemicubeFace::Top)
                for (int x = f.viewport.x; x < f.viewport.x + f.viewport.width; ++x)
                    horizon += half.delta_ff()[static_cast<std::size_t>(f.viewport.y) * HW + x];
        EXPECT_NEAR(far_a, far_b, bound + horizon) << "row " << p << " normal " << pa.normal.x << " " << pa.normal.y << " "
                                                   << pa.normal.z << " centroid " << pa.centroid.x << " " << pa.centroid.y
                                                   << " " << pa.centroid.z;
        std::printf("row %u: far sum range-limited %.6f, plain %.6f, bound %.1e (%d pixels)\n", p, far_a, far_b, bound,
                    reach);
    }
    EXPECT_GT(near_checked, 0u);
}

// Off, and auto on a scene below the piece threshold, are the plain rows, bit for bit.
TEST(RangeLimitedSubHemicubes, OffAndBelowTheThresholdArePlainRows) {
    const Shadow s;
    HemicubeOptions o;
    o.resolution = 128;
    o.threads = 1;
    const std::vector<std::uint32_t> rows{s.sender, s.occluder};
    const std::vector<Plan> plans{Plan::sampled_fine, Plan::sampled};
    o.sub_hemicube_range = HemicubeOptions::SubHemicubeRange::automatic;
    HemicubeStats st;
    const auto below = rows_of(s.scene, o, rows, plans, &st);  // 3 pieces < 1,000
    EXPECT_EQ(st.range_limited_rows, 0u);
    o.sub_hemicube_range = HemicubeOptions::SubHemicubeRange::off;
    o.sub_hemicube_range_min_pieces = 1;
    const auto off = rows_of(s.scene, o, rows, plans, &st);
    EXPECT_EQ(st.range_limited_rows, 0u);
    for (std::uint32_t p : rows) {
        EXPECT_EQ(below.at(p).col, off.at(p).col);
        EXPECT_EQ(below.at(p).val, off.at(p).val);
    }
}

}  // namespace
}  // namespace ffcube
