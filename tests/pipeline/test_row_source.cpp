// The composition root: options parsed once, one factory, and the rows it gives are the rows of
// the layers composed by hand (so every front end that calls it gets the same rows).
#include <gtest/gtest.h>

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>

#include "ffcube/core/error.hpp"
#include "ffcube/formfactor/row_provider.hpp"
#include "ffcube/io/report.hpp"
#include "ffcube/pipeline/form_factors.hpp"
#include "ffcube/pipeline/row_source.hpp"
#include "ffcube/scene/patch_areas.hpp"
#include "support/scenes.hpp"

namespace ffcube {
namespace {

std::string error_of(const auto& f) {
    try {
        f();
    } catch (const InputError& e) {
        return e.what();
    }
    return "";
}

TEST(PipelineOptions, WordsRoundTripAndBadWordsNameTheOption) {
    for (RowMethod m : {RowMethod::Hemicube, RowMethod::Raycast}) EXPECT_EQ(parse_row_method(to_string(m)), m);
    for (Correction c : {Correction::None, Correction::Near}) EXPECT_EQ(parse_correction(to_string(c)), c);
    for (FarFieldMode f : {FarFieldMode::automatic, FarFieldMode::on, FarFieldMode::off})
        EXPECT_EQ(parse_far_field(to_string(f)), f);
    for (EnforceRequest e :
         {EnforceRequest::None, EnforceRequest::Reciprocity, EnforceRequest::Closure, EnforceRequest::Both})
        EXPECT_EQ(parse_enforce_request(to_string(e)), e);
    EXPECT_NE(error_of([] { parse_row_method("hemicubes"); }).find("--method hemicubes"), std::string::npos);
    EXPECT_NE(error_of([] { parse_correction("far"); }).find("--correct far"), std::string::npos);
    EXPECT_NE(error_of([] { parse_far_field("yes"); }).find("--far-field yes"), std::string::npos);
    EXPECT_NE(error_of([] { parse_enforce_request("all"); }).find("--enforce all"), std::string::npos);
    EXPECT_EQ(enforce_mode(EnforceRequest::Both), EnforceMode::Closure);
    EXPECT_EQ(enforce_mode(EnforceRequest::Reciprocity), EnforceMode::Reciprocity);
}

TEST(PipelineOptions, OneResolutionRule) {
    RowOptions o;
    for (int bad : {7, 6, 9, 8194, -8, 0}) {
        o.resolution = bad;
        EXPECT_EQ(error_of([&] { validate(o); }),
                  fmt::format("--resolution {}: must be an even number of pixels from 8 to 8192", bad));
    }
    for (int good : {8, 10, 256, 8192}) {
        o.resolution = good;
        EXPECT_NO_THROW(validate(o));
    }
    // The ray caster has no resolution; it has rays.
    o.method = RowMethod::Raycast;
    o.resolution = 7;
    EXPECT_NO_THROW(validate(o));
    o.rays = 0;
    EXPECT_NE(error_of([&] { validate(o); }).find("--rays 0"), std::string::npos);
}

// --method auto: the ray caster where rays_preferred (pipeline/row_engine.hpp) (here separate tiles, one
// piece each: 1,000 or more pieces, or 100 or more of at most 4 patches each), at the fine-row
// ray count for the resolution unless --rays or --fine-row-rays says otherwise; the hemicube
// below that, with obstruction-only surfaces, or with --fine-rows hemicubes; options without
// method_auto unchanged. The reason is kept for the report; the words parse into the same options.
TEST(PipelineOptions, MethodAutoFollowsThePieces) {
    const auto tiles = [](std::size_t n, double edge = 2.0) {  // edge 0.5: 4 patches a tile, 0.4: 9
        std::vector<test::NamedPolygon> polys;
        for (std::size_t k = 0; k < n; ++k) {
            const double x = static_cast<double>(k % 40) * 1.5, y = static_cast<double>(k / 40) * 1.5;
            polys.push_back({"t" + std::to_string(k), {{x, y, 0}, {x + 1, y, 0}, {x + 1, y + 1, 0}, {x, y + 1, 0}}});
        }
        return test::make_scene(polys, edge * (1 + 1e-9));
    };
    const std::size_t min = kFineRowsByRaysMinPieces;
    RowOptions o;
    set_row_method("auto", o);
    EXPECT_TRUE(o.method_auto);
    o.resolution = 128;
    Scene many = tiles(min);
    RowOptions r = resolve_row_method(o, many);
    EXPECT_EQ(r.method, RowMethod::Raycast);
    EXPECT_FALSE(r.method_auto);
    EXPECT_TRUE(r.auto_raycast);
    EXPECT_EQ(r.rays, 32768u);  // max(N²/2, min(2 N², 32,768)) at N = 128
    EXPECT_EQ(r.method_choice, fmt::format("auto: {} pieces, {} or more", min, min));
    EXPECT_EQ(resolve_row_method(r, many).rays, 32768u);  // resolved once: a second call keeps it
    o.resolution = 64;
    EXPECT_EQ(resolve_row_method(o, many).rays, 8192u);
    RowOptions given = o;
    given.rays = 1000, given.rays_given = true;
    EXPECT_EQ(resolve_row_method(given, many).rays, 1000u);
    given = o;
    given.fine_row_rays = 2048;
    EXPECT_EQ(resolve_row_method(given, many).rays, 2048u);
    given = o;
    given.fine_rows = FineRows::hemicubes;
    EXPECT_EQ(resolve_row_method(given, many).method, RowMethod::Hemicube);
    const std::size_t mesh = kRaysMinMeshPieces;
    EXPECT_EQ(resolve_row_method(o, tiles(mesh - 1)).method, RowMethod::Hemicube);
    const RowOptions small_mesh = resolve_row_method(o, tiles(mesh, 0.5));  // 4 patches a piece
    EXPECT_EQ(small_mesh.method, RowMethod::Raycast);
    EXPECT_EQ(small_mesh.method_choice, "auto: 100 pieces of 400 patches, 100 or more of at most 4 patches each");
    const RowOptions subdivided = resolve_row_method(o, tiles(mesh, 0.4));  // 9 patches a piece
    EXPECT_EQ(subdivided.method, RowMethod::Hemicube);
    EXPECT_EQ(subdivided.method_choice,
              "auto: 100 pieces of 900 patches: rays need 1000 pieces, or 100 of at most 4 patches each");
    EXPECT_EQ(resolve_row_method(o, tiles(min - 1, 0.4)).method, RowMethod::Hemicube);
    many.obstruction_first = static_cast<std::uint32_t>(many.size() - 1);
    r = resolve_row_method(o, many);
    EXPECT_EQ(r.method, RowMethod::Hemicube);
    EXPECT_EQ(r.method_choice, fmt::format("auto: {} pieces, obstruction-only surfaces", min));
    many.obstruction_first = std::numeric_limits<std::uint32_t>::max();
    RowOptions named;
    set_row_method("hemicube", named);
    EXPECT_FALSE(named.method_auto);
    EXPECT_EQ(resolve_row_method(named, many).method, RowMethod::Hemicube);
    EXPECT_TRUE(resolve_row_method(named, many).method_choice.empty());
    set_row_method("raycast", named);
    EXPECT_EQ(named.method, RowMethod::Raycast);
    EXPECT_NE(error_of([&] { set_row_method("rays", named); }).find("must be auto, hemicube or raycast"), std::string::npos);
}

// What .ffm files and checkpoints record: these strings are compared when a run resumes or a
// matrix is read back, so they must not drift with refactoring.
TEST(PipelineOptions, MetadataIsStable) {
    RowOptions o;
    FfmMetadata m = row_metadata(o);
    EXPECT_EQ(m.method, "hemicube");
    EXPECT_EQ(m.resolution, 256u);
    EXPECT_EQ(m.settings, "rotate=1 seed=24301 correct=near k=3");
    o.rotate = false;
    o.far_field = FarFieldMode::off;
    o.near_k = 2.5;
    EXPECT_EQ(row_metadata(o).settings, "rotate=0 seed=24301 correct=near k=2.5 far_field=off");
    o.method = RowMethod::Raycast;
    o.rays = 1000;
    o.correct = Correction::None;
    m = row_metadata(o);
    EXPECT_EQ(m.method, "raycast");
    EXPECT_EQ(m.resolution, 0u);
    EXPECT_EQ(m.settings, "rays=1000 seed=24301 sampler=sobol");
}

void expect_same_rows(const CsrMatrix& a, const CsrMatrix& b) {
    ASSERT_EQ(a.size(), b.size());
    for (std::uint32_t i = 0; i < a.size(); ++i) {
        const RowView x = a.row(i), y = b.row(i);
        ASSERT_EQ(x.col.size(), y.col.size()) << "row " << i;
        for (std::size_t k = 0; k < x.col.size(); ++k) {
            EXPECT_EQ(x.col[k], y.col[k]) << "row " << i;
            // Bitwise: the same computation, not merely close.
            EXPECT_EQ(std::memcmp(&x.val[k], &y.val[k], sizeof(float)), 0) << "row " << i << " entry " << k;
        }
    }
}

// A closed box with a blocker: near pairs along every edge (exact values), a possibly occluded
// pair (sub-hemicubes) and far pairs (the far field when on).
Scene box_scene() {
    std::vector<NamedPolygon> polys = test::inward_box(1.0, 1.0, 1.0);
    polys.push_back(test::square_z("blocker", 0.4, true, 0.3, Vec3(0.35, 0.35, 0.0)));
    return test::make_scene(polys, 0.25);
}

TEST(RowSource, FactoryRowsAreTheHandComposedRows) {
    const Scene scene = box_scene();
    for (FarFieldMode ff : {FarFieldMode::off, FarFieldMode::on}) {
        RowOptions o;
        o.resolution = 32;
        o.threads = 2;
        o.far_field = ff;
        RowSource rows = make_row_source(scene, o);
        ASSERT_NE(rows.corrected(), nullptr);
        ASSERT_NE(rows.hemicube(), nullptr);
        EXPECT_EQ(rows.raycast(), nullptr);
        const CsrMatrix F = compute_all_rows(rows.provider());
        // provider() is the correction, seen through the ledger: every row's figures noted.
        ASSERT_EQ(rows.ledger().size(), scene.size());
        for (std::uint32_t i = 0; i < scene.size(); ++i) {
            EXPECT_GE(rows.ledger().measures()[i], 0) << i;
            EXPECT_GE(rows.ledger().errors()[i], 0.0f) << i;
        }

        HemicubeOptions h;
        h.resolution = 32;
        h.threads = 1;  // rows do not depend on the thread count
        HemicubeRowProvider hemi(scene, h);
        NearFieldOptions nf = near_field_options_for_hemicube(32, 3.0);
        nf.far_field = ff;
        CorrectedRowProvider corrected(scene, hemi, nf);
        expect_same_rows(F, compute_all_rows(corrected));
    }
}

// Forwards to a hemicube provider but keeps RowProvider's own compute_rows_staged: the plans and
// corrections on the calling thread, one row after the other, as before they ran on the
// hemicube's workers.
class CallingThreadStages final : public RowProvider {
public:
    explicit CallingThreadStages(HemicubeRowProvider& h) : h_(h) {}
    std::uint32_t size() const override { return h_.size(); }
    std::string name() const override { return h_.name(); }
    void compute_rows(std::span<const std::uint32_t> rows, const RowSink& sink) override { h_.compute_rows(rows, sink); }
    bool can_sample_sender() const override { return true; }
    void compute_rows_requested(std::span<const std::uint32_t> rows, std::span<const RowRequest> requests,
                                const RowSink& sink) override {
        h_.compute_rows_requested(rows, requests, sink);
    }

private:
    HemicubeRowProvider& h_;
};

// The correction runs on the hemicube's workers (each corrects the rows it measured): the rows,
// their error estimates and the correction's counts are those of the correction on the calling
// thread, bitwise, at 1 and 3 workers, processes or threads, far field off and on.
TEST(RowSource, CorrectedRowsDoNotDependOnWhereTheCorrectionRuns) {
    // The box with the blocker on its floor (with the far field, rows not measured at all), and
    // the box with a shelf 0.15 above the floor instead: floor patches and their near neighbours
    // on the walls are pairs the shelf may occlude (sub-hemicube rows).
    std::vector<NamedPolygon> polys = test::inward_box(1.0, 1.0, 1.0);
    polys.push_back(test::square_z("shelf", 0.15, true, 0.5, Vec3(0.25, 0.25, 0.0)));
    const Scene scenes[] = {box_scene(), test::make_scene(polys, 0.25)};
    std::uint64_t sampled = 0, analytic = 0, replaced = 0;
    for (const Scene& scene : scenes) {
        for (FarFieldMode ff : {FarFieldMode::off, FarFieldMode::on}) {
            NearFieldOptions nf = near_field_options_for_hemicube(32, 3.0);
            nf.far_field = ff;
            HemicubeOptions h;
            h.resolution = 32;
            h.threads = 1;
            HemicubeRowProvider one(scene, h);
            CallingThreadStages calling(one);
            CorrectedRowProvider reference(scene, calling, nf);
            RowLedger reference_figures;
            const CsrMatrix F = compute_all_rows(reference, &reference_figures);
            const NearFieldStats& r = reference.stats();
            sampled += r.rows_sampled;
            analytic += r.rows_analytic;
            replaced += r.replaced;
            for (const bool processes : {true, false}) {
                h.threads = 3;
                h.worker_processes = processes;
                HemicubeRowProvider three(scene, h);
                CorrectedRowProvider staged(scene, three, nf);
                SCOPED_TRACE(fmt::format("{} patches, far field {}, {}", scene.size(), to_string(ff),
                                         processes ? "processes" : "threads"));
                RowLedger staged_figures;
                expect_same_rows(F, compute_all_rows(staged, &staged_figures));
                const NearFieldStats& s = staged.stats();
                EXPECT_EQ(s.rows, r.rows);
                EXPECT_EQ(s.rows_sampled, r.rows_sampled);
                EXPECT_EQ(s.replaced, r.replaced);
                EXPECT_EQ(s.refused, r.refused);
                EXPECT_EQ(s.quadrature, r.quadrature);
                EXPECT_EQ(s.rows_closed, r.rows_closed);
                EXPECT_EQ(s.rows_analytic, r.rows_analytic);
                EXPECT_EQ(s.far_entries, r.far_entries);
                EXPECT_EQ(s.closed_scale_max_change, r.closed_scale_max_change);
                EXPECT_EQ(s.inner_row_sum_min, r.inner_row_sum_min);
                EXPECT_TRUE(std::ranges::equal(staged_figures.errors(), reference_figures.errors()));
                EXPECT_TRUE(std::ranges::equal(staged_figures.measures(), reference_figures.measures()));
                EXPECT_EQ(staged.retained_analysis_entries(), 0u);
            }
        }
    }
    // Every kind of row went through: sub-hemicubes (a possibly occluded near pair), exact near
    // values, and rows made wholly of analytic values (not measured).
    EXPECT_GT(sampled, 0u);
    EXPECT_GT(analytic, 0u);
    EXPECT_GT(replaced, 0u);
}

TEST(RowSource, PlainAndRaycastSources) {
    const Scene scene = box_scene();
    RowOptions o;
    o.resolution = 16;
    o.correct = Correction::None;
    RowSource plain = make_row_source(scene, o);
    EXPECT_EQ(plain.corrected(), nullptr);
    // The hemicube's rows through the driver (which engine measures each row): the same rows.
    ASSERT_NE(plain.driver(), nullptr);
    HemicubeRowProvider hemi(scene, hemicube_options(o));
    expect_same_rows(compute_all_rows(plain.provider()), compute_all_rows(hemi));
    // Without the correction no row has figures: none noted.
    EXPECT_FALSE(plain.ledger().any_figures());
    EXPECT_TRUE(std::isnan(plain.ledger().errors()[0]));

    o.method = RowMethod::Raycast;
    o.rays = 64;
    RowSource rays = make_row_source(scene, o);
    ASSERT_NE(rays.raycast(), nullptr);
    EXPECT_EQ(rays.hemicube(), nullptr);
    RaycastRowProvider direct(scene, raycast_options(o));
    expect_same_rows(compute_all_rows(rays.provider()), compute_all_rows(direct));

    // The report names what ran.
    Report r;
    report_row_source(r, rays);
    const std::string text = r.dump();
    EXPECT_NE(text.find("\"method\": \"raycast\""), std::string::npos) << text;
    EXPECT_NE(text.find("\"rays_per_patch\": 64"), std::string::npos) << text;
}

// Every row through the one path (pipeline/form_factors.hpp), enforced as rows.options() asks,
// into memory.
CsrMatrix finished_matrix(RowSource& rows, const Scene& scene, Report& report) {
    return form_factor_matrix(scene, rows, report);
}

TEST(RowSource, ClosureIsRefusedForAnOpenScene) {
    // Two facing squares: light escapes at the sides, so closure would hide it.
    const Scene scene = test::make_scene({test::square_z("a", 0, true), test::square_z("b", 1, false)}, 0.5);
    RowOptions o;
    o.resolution = 16;
    o.enforce = EnforceRequest::Closure;
    Report r;
    // Plain hemicubes: the evidence is the pixels that saw nothing.
    o.correct = Correction::None;
    RowSource plain = make_row_source(scene, o);
    const std::string e1 = error_of([&] { finished_matrix(plain, scene, r); });
    EXPECT_NE(e1.find("--enforce closure: hemicube pixels saw nothing"), std::string::npos) << e1;
    // Corrected: here every row is analytic (the far field proves both pairs), no pixel is
    // rendered, and the evidence is the row sum before correction (F = 0.19982 for this pair).
    o.correct = Correction::Near;
    RowSource rows = make_row_source(scene, o);
    const std::string e2 = error_of([&] { finished_matrix(rows, scene, r); });
    EXPECT_NE(e2.find("--enforce closure: a row sums to 0.19982"), std::string::npos) << e2;
    // Reciprocity needs no closed scene, and makes A_i G_ij = A_j G_ji: G's exchange areas are one
    // double per pair, each direction then divided by its area and rounded to float (relative
    // error at most 2^-24 each), so the two products differ by at most 2^-24 of their sum, plus
    // the double products' own rounding (2^-53 each, far below): 2^-23 of the larger is a bound.
    RowOptions recip = o;
    recip.enforce = EnforceRequest::Reciprocity;
    RowSource rows2 = make_row_source(scene, recip);
    const CsrMatrix G = finished_matrix(rows2, scene, r);
    ASSERT_EQ(G.size(), scene.size());
    const std::vector<double> A = patch_areas(scene);
    std::size_t pairs = 0;
    for (std::uint32_t i = 0; i < G.size(); ++i)
        for (std::uint32_t j = 0; j < G.size(); ++j) {
            const double a = A[i] * G.at(i, j), b = A[j] * G.at(j, i);
            if (i != j && a > 0) ++pairs;
            EXPECT_LE(std::abs(a - b), std::ldexp(std::max(a, b), -23)) << i << " " << j;
        }
    EXPECT_GT(pairs, 0u);  // the squares see each other
    // The report carries the enforcement's figures: before, reciprocity was not exact.
    const std::string text = r.dump();
    EXPECT_NE(text.find("\"mode\": \"reciprocity\""), std::string::npos) << text;
}

}  // namespace
}  // namespace ffcube
