// Property test of issue 43, part 5 (docs/robustness.md, "No row out of range"): seeded random
// triangle soups with the defects real exports have (duplicates, faces that cross, slivers,
// offsets far from the origin) run through the real row pipeline (load_and_mesh, make_row_source,
// the hemicube with the near-field correction, as `ffcube formfactors` runs them). Every run
// either refuses the scene with an InputError or gives rows whose entries are in [0, 1] and whose
// sums are at most 1 + tolerance. The soups are also meshed without the defect checks
// (build_scene alone) to exercise the last guard, the corrected rows' range check, on geometry
// that the loader would have refused.
#include <gtest/gtest.h>

#include <fmt/format.h>

#include <cmath>
#include <cstdint>
#include <string>
#include <vector>

#include "ffcube/core/error.hpp"
#include "ffcube/formfactor/row_provider.hpp"
#include "ffcube/io/report.hpp"
#include "ffcube/pipeline/row_source.hpp"
#include "ffcube/pipeline/scene_loading.hpp"
#include "ffcube/scene/mesher.hpp"
#include "ffcube/scene/obj_loader.hpp"
#include "support/scenes.hpp"
#include "support/temp_files.hpp"

namespace ffcube {
namespace {

// SplitMix64: the same numbers on every platform and standard library (std::uniform_real_
// distribution is not specified bit for bit).
struct Draw {
    std::uint64_t s;
    std::uint64_t next() {
        std::uint64_t z = (s += 0x9E3779B97F4A7C15ull);
        z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
        z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
        return z ^ (z >> 31);
    }
    double unit() { return static_cast<double>(next() >> 11) * 0x1.0p-53; }
    double in(double lo, double hi) { return lo + (hi - lo) * unit(); }
    bool chance(double p) { return unit() < p; }
};

// A soup: the inward unit box (a closed enclosure, so that its rows should sum to 1) and a few
// random triangles inside it, some duplicated (the same winding, or reversed: a two-sided sheet),
// some slivers (a vertex 1e-4 of the edge off the opposite edge), all offset by up to 1e14.
std::vector<test::NamedPolygon> soup(Draw& d, Vec3& offset) {
    std::vector<test::NamedPolygon> polys = test::inward_box(1, 1, 1);
    const int n = 2 + static_cast<int>(d.next() % 3);
    for (int k = 0; k < n; ++k) {
        test::NamedPolygon t{fmt::format("t{}", k), {}};
        for (int v = 0; v < 3; ++v) t.vertices.push_back(Vec3(d.in(0.1, 0.9), d.in(0.1, 0.9), d.in(0.1, 0.9)));
        if (d.chance(0.25)) t.vertices[2] = 0.5 * (t.vertices[0] + t.vertices[1]) + Vec3(1e-4, -1e-4, 1e-4);  // sliver
        polys.push_back(t);
        if (d.chance(0.3)) polys.push_back({t.object + "_copy", t.vertices});  // duplicate
        if (d.chance(0.2)) polys.push_back({t.object + "_back", {t.vertices[2], t.vertices[1], t.vertices[0]}});
    }
    const double exps[] = {0, 0, 5, 12, 14};
    const double e = exps[d.next() % 5];
    offset = e > 0 ? Vec3(std::pow(10.0, e), 0, -std::pow(10.0, e - 1)) : Vec3(0.0);
    for (auto& p : polys)
        for (Vec3& v : p.vertices) v += offset;
    return polys;
}

std::string obj_text(const std::vector<test::NamedPolygon>& polys) {
    std::string s;
    std::size_t n = 0;
    for (const auto& p : polys) {
        s += "o " + p.object + "\n";
        for (const Vec3& v : p.vertices) s += fmt::format("v {:.17g} {:.17g} {:.17g}\n", v.x, v.y, v.z);
        s += "f";
        for (std::size_t k = 0; k < p.vertices.size(); ++k) s += fmt::format(" {}", ++n);
        s += "\n";
    }
    return s;
}

// Entries in [0, 1] and sums at most 1 + tol. tol: the range check admits 1e-7 over 1 in double
// (kClosedRowTolerance, src/accuracy/row_range.hpp); CsrMatrix stores floats (2^-24 relative
// each), which moves a sum of 1 by at most 6e-8 more: 2e-7 covers both.
constexpr double kSumTolerance = 2e-7;

void expect_rows_in_range(const CsrMatrix& F, const std::string& what) {
    for (std::uint32_t i = 0; i < F.size(); ++i) {
        const RowView row = F.row(i);
        double sum = 0;
        for (std::size_t k = 0; k < row.val.size(); ++k) {
            const double v = row.val[k];
            ASSERT_TRUE(std::isfinite(v) && v >= 0.0 && v <= 1.0) << what << ": row " << i << " entry " << v;
            sum += v;
        }
        ASSERT_LE(sum, 1.0 + kSumTolerance) << what << ": row " << i;
    }
}

RowOptions row_options() {
    RowOptions o;
    o.resolution = 32;
    o.threads = 1;
    return o;
}

TEST(DefectSoups, EveryRowIsInRangeOrTheSceneIsRefused) {
    test::TempFiles dir;
    Draw d{20260143};
    int refused = 0, computed = 0;
    std::uint64_t recomputed = 0;
    for (int s = 0; s < 10; ++s) {
        Vec3 offset;
        const auto polys = soup(d, offset);
        const std::string what = fmt::format("soup {} (offset {})", s, offset.x);
        // Through the loader and its checks, as the command line runs it.
        SceneOptions so;
        so.path = dir.write(fmt::format("soup{}.obj", s), obj_text(polys)).string();
        so.patches = 60;
        Report report;
        try {
            const Scene scene = load_and_mesh(so, report);
            RowSource rows = make_row_source(scene, row_options());
            expect_rows_in_range(compute_all_rows(rows.provider()), what + ", loaded");
            ++computed;
        } catch (const InputError& e) {
            ++refused;  // refused cleanly: named
            EXPECT_NE(std::string(e.what()).find("soup"), std::string::npos) << e.what();
        }
        // Without the checks: the rows of whatever the mesher makes of it still stay in range,
        // or the row is refused by name.
        MeshOptions mo;
        mo.target_patches = 60;
        const Scene raw = build_scene(model_from_polygons(polys, what), mo);
        try {
            RowSource rows = make_row_source(raw, row_options());
            expect_rows_in_range(compute_all_rows(rows.provider()), what + ", unchecked");
            recomputed += rows.corrected()->stats().rows_recomputed_out_of_range;
        } catch (const InputError& e) {
            EXPECT_NE(std::string(e.what()).find("patch "), std::string::npos) << e.what();
        }
    }
    std::printf("soups: %d refused, %d computed; unchecked soups: %llu rows out of range handed on as measured\n", refused,
                computed, static_cast<unsigned long long>(recomputed));
    EXPECT_GT(refused, 0);   // the draw has crossings
    EXPECT_GT(computed, 0);  // and soups that are fine
}

}  // namespace
}  // namespace ffcube
