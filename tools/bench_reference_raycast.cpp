// An independent check of the Cornell box's object-radiosity reference (issue 16; docs/adaptive.md,
// "The reference, checked with the ray caster"). It solves the built-in Cornell box (contact cuts
// auto) on one mesh, with hemicube rows or ray-cast rows, and prints each object's mean luminance
// (Σ A_i lum(B_i) / Σ A_i, lum = 0.2126 r + 0.7152 g + 0.0722 b, as tools/bench_adaptive.sh) to 9
// digits, so that runs on different meshes and methods can be compared to 1e-5.
//
//   ./build/tools/bench_reference_raycast [--max-patch-edge L] [--split S] [--method hemicube|raycast]
//        [--rays N] [--light-rays M] [--seeds "K1 K2 ..."] [--threads T] [--resolution R] [--correct near|none]
//
//   --max-patch-edge L  the mesh: 0 (the default: --patches 2000, L = 43.02), or L as ffcube's option;
//   --split S           then every patch split S × S (refine_patches): the nested mesh of
//                       tools/bench_floor_bias (S = 2: its "fine" run);
//   --rays N            ray-cast rows: rays per row of every patch that does not emit (default 4096);
//   --light-rays M      rays per row of the emitting patches (default N). The light's few rows carry
//                       the direct term, and their Monte Carlo noise does not average over receivers
//                       (docs/adaptive.md derives the choice); M ≫ N buys that noise down for the cost
//                       of a few rows only;
//   --seeds "K ..."     one solve per seed (ray caster; the hemicube takes one); with two or more the
//                       spread is printed: s = the sample standard deviation over the seeds of one
//                       run's value (two seeds: |a − b| / √2), and s / √k that of their mean.
//
// Experiments of issue 16 part 2 (docs/adaptive.md, "The default within 0.1%"): some rows from a
// second source with other settings, the rest as above:
//   --light-resolution R, --light-far-field auto|on|off, --light-method hemicube|raycast
//                       the second source's settings (any of them makes one); its rows are the
//                       emitting patches' and
//   --fine-share S      the rows that receive the largest first-bounce power from the emitting
//                       rows, until they carry the share S of it;
//   --fine-objects "a,b" every row of these objects;  --fine-rows "i j ..." these rows;
//   DIFF_OBJECT=name    (environment) prints each row of that object from both sources: its sums
//                       and the second minus the first per receiving object.
//
// Each solve also prints the luminance of the power escaped (the box's open front) over the emitted.
// Everything else is ffcube solve's default (near-field correction on, shooting to 1e-4); one
// thread unless --threads (rows do not depend on it).
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <algorithm>
#include <map>
#include <sstream>
#include <string>
#include <vector>

#include "ffcube/io/report.hpp"
#include "ffcube/pipeline/options.hpp"
#include "ffcube/pipeline/row_source.hpp"
#include "ffcube/pipeline/scene_loading.hpp"
#include "ffcube/scene/refine.hpp"
#include "ffcube/solver/solver.hpp"

namespace {

using namespace ffcube;

double luminance(const Vec3& b) { return 0.2126 * b.r + 0.7152 * b.g + 0.0722 * b.b; }

// Rows of emitting patches from one provider, the rest from another; rows reach the sink in list
// order (each provider's rows are buffered until the list is done).
class SplitRowProvider final : public RowProvider {
public:
    SplitRowProvider(RowProvider& light, RowProvider& rest, std::vector<bool> emits)
        : light_(light), rest_(rest), emits_(std::move(emits)) {}
    std::uint32_t size() const override { return rest_.size(); }
    std::string name() const override { return "split(" + light_.name() + ", " + rest_.name() + ")"; }
    void compute_rows(std::span<const std::uint32_t> rows, const RowSink& sink) override {
        std::vector<std::uint32_t> a, b;
        for (std::uint32_t r : rows) (emits_[r] ? a : b).push_back(r);
        std::vector<SparseRow> ra(a.size()), rb(b.size());
        std::size_t k = 0;
        light_.compute_rows(a, [&](std::uint32_t i, const SparseRow& row) {
            ra[k++] = row;
            light_rows_.emplace(i, row);
        });
        k = 0;
        rest_.compute_rows(b, [&](std::uint32_t, const SparseRow& row) { rb[k++] = row; });
        std::size_t ia = 0, ib = 0;
        for (std::uint32_t r : rows) sink(r, emits_[r] ? ra[ia++] : rb[ib++]);
    }

    // The emitting rows as first measured, by patch.
    const std::map<std::uint32_t, SparseRow>& light_rows() const { return light_rows_; }

private:
    std::map<std::uint32_t, SparseRow> light_rows_;
    RowProvider& light_;
    RowProvider& rest_;
    std::vector<bool> emits_;
};

std::vector<double> object_means(const Scene& scene, const SolveResult& r) {
    std::vector<double> a(scene.objects.size(), 0.0), p(scene.objects.size(), 0.0);
    for (std::size_t i = 0; i < scene.size(); ++i) {
        a[scene.patches[i].object] += scene.patches[i].area;
        p[scene.patches[i].object] += scene.patches[i].area * luminance(r.radiosity[i]);
    }
    for (std::size_t o = 0; o < a.size(); ++o) p[o] /= a[o];
    return p;
}

}  // namespace

int main(int argc, char** argv) try {
    RowOptions rows;
    rows.threads = 1;
    std::uint64_t light_rays = 0;
    int light_resolution = 0;
    std::string fine_objects, fine_rows, light_far_field, light_method;
    double fine_share = 0;  // experiment: also the rows whose first shot covers this share of the first bounce's power
    std::uint32_t split = 1;
    std::vector<std::uint64_t> seeds{rows.seed};
    SceneOptions so;
    so.patches = 2000;
    for (int a = 1; a + 1 < argc; a += 2) {
        const std::string k = argv[a], v = argv[a + 1];
        if (k == "--max-patch-edge") {
            so.max_patch_edge = std::atof(v.c_str());
            if (so.max_patch_edge > 0) so.patches = 0;
        } else if (k == "--split") split = static_cast<std::uint32_t>(std::atoi(v.c_str()));
        else if (k == "--method") rows.method = parse_row_method(v);
        else if (k == "--rays") rows.rays = std::strtoull(v.c_str(), nullptr, 10);
        else if (k == "--light-rays") light_rays = std::strtoull(v.c_str(), nullptr, 10);
        else if (k == "--threads") rows.threads = static_cast<unsigned>(std::atoi(v.c_str()));
        else if (k == "--resolution") rows.resolution = std::atoi(v.c_str());
        else if (k == "--light-resolution") light_resolution = std::atoi(v.c_str());
        else if (k == "--fine-share") fine_share = std::atof(v.c_str());
        else if (k == "--fine-objects") fine_objects = v;
        else if (k == "--fine-rows") fine_rows = v;
        else if (k == "--light-far-field") light_far_field = v;
        else if (k == "--light-method") light_method = v;
        else if (k == "--correct") rows.correct = parse_correction(v);
        else if (k == "--seeds") {
            seeds.clear();
            std::istringstream in(v);
            for (std::uint64_t s; in >> s;) seeds.push_back(s);
        } else {
            std::fprintf(stderr, "bench_reference_raycast: unknown option %s (see the comment at the top of "
                                 "tools/bench_reference_raycast.cpp)\n", k.c_str());
            return 2;
        }
    }
    if (argc % 2 == 0 || split < 1 || seeds.empty()) {
        std::fprintf(stderr, "bench_reference_raycast: options come in pairs, --split is at least 1 and --seeds names at "
                             "least one seed (see the comment at the top of tools/bench_reference_raycast.cpp)\n");
        return 2;
    }
    if (rows.method == RowMethod::Hemicube) seeds.resize(1);
    if (light_rays == 0) light_rays = rows.rays;
    validate(rows);
    Report report;
    const Scene base = load_and_mesh(so, report);
    const Scene scene = split > 1 ? refine_patches(base, std::vector<std::uint32_t>(base.size(), split)).scene : base;
    std::vector<bool> emits(scene.size());
    std::size_t emitters = 0;
    for (std::size_t i = 0; i < scene.size(); ++i) {
        const Vec3& e = scene.materials[scene.patches[i].material].ke;
        emits[i] = e.r > 0 || e.g > 0 || e.b > 0;
        emitters += emits[i];
    }
    std::printf("mesh: %s, split %u x %u: %zu patches, %zu emitting; method %s", scene.stats.how.c_str(), split, split,
                scene.size(), emitters, std::string(to_string(rows.method)).c_str());
    if (rows.method == RowMethod::Raycast)
        std::printf(", %llu rays per row, %llu per emitting row", static_cast<unsigned long long>(rows.rays),
                    static_cast<unsigned long long>(light_rays));
    std::printf("\n");

    std::vector<std::vector<double>> values;  // per seed, per object
    std::vector<double> f_light, direct;         // per object, the first seed's (see below)
    for (std::uint64_t seed : seeds) {
        rows.seed = seed;
        RowSource rest = make_row_source(scene, rows);
        RowOptions lo = rows;
        lo.rays = light_rays;
        if (light_resolution > 0) lo.resolution = light_resolution;
        if (!light_far_field.empty()) lo.far_field = parse_far_field(light_far_field);
        if (!light_method.empty()) lo.method = parse_row_method(light_method);
        RowSource light;
        const bool own_light = rows.method == RowMethod::Raycast ? light_rays != rows.rays
                                                                 : (light_resolution > 0 && light_resolution != rows.resolution) || !light_far_field.empty() || !light_method.empty();
        if (own_light) light = make_row_source(scene, lo);
        std::vector<bool> fine = emits;
        if (own_light && fine_share > 0) {
            std::vector<std::uint32_t> lr;
            for (std::uint32_t i = 0; i < scene.size(); ++i)
                if (emits[i]) lr.push_back(i);
            std::vector<double> pw(scene.size(), 0.0);
            light.provider().compute_rows(lr, [&](std::uint32_t l, const SparseRow& row) {
                const Patch& p = scene.patches[l];
                for (std::size_t e = 0; e < row.col.size(); ++e) {
                    const Patch& q = scene.patches[row.col[e]];
                    pw[row.col[e]] += luminance(scene.materials[q.material].kd * scene.materials[p.material].ke) * p.area * row.val[e];
                }
            });
            std::vector<std::uint32_t> order(scene.size());
            for (std::uint32_t i = 0; i < scene.size(); ++i) order[i] = i;
            std::sort(order.begin(), order.end(), [&](auto a, auto b) { return pw[a] > pw[b] || (pw[a] == pw[b] && a < b); });
            double tot = 0, acc = 0;
            for (double x : pw) tot += x;
            std::size_t nf = 0;
            for (std::uint32_t i : order) {
                if (acc >= fine_share * tot) break;
                acc += pw[i];
                if (!fine[i]) ++nf;
                fine[i] = true;
            }
            std::printf("fine rows: %zu emitting + %zu carrying %.1f%% of the first bounce\n", emitters, nf, 100 * acc / tot);
        }
        if (std::getenv("DIFF_OBJECT") && own_light) {
            const std::string obj = std::getenv("DIFF_OBJECT");
            std::vector<std::uint32_t> rr;
            for (std::uint32_t i = 0; i < scene.size(); ++i)
                if (scene.objects[scene.patches[i].object] == obj) rr.push_back(i);
            std::vector<std::vector<double>> sa(rr.size(), std::vector<double>(scene.objects.size())), sb = sa;
            std::size_t k = 0;
            rest.provider().compute_rows(rr, [&](std::uint32_t, const SparseRow& row) {
                for (std::size_t e = 0; e < row.col.size(); ++e) sa[k][scene.patches[row.col[e]].object] += row.val[e];
                ++k;
            });
            k = 0;
            light.provider().compute_rows(rr, [&](std::uint32_t, const SparseRow& row) {
                for (std::size_t e = 0; e < row.col.size(); ++e) sb[k][scene.patches[row.col[e]].object] += row.val[e];
                ++k;
            });
            for (std::size_t r = 0; r < rr.size(); ++r) {
                const Vec3 c = scene.patches[rr[r]].centroid;
                double ta = 0, tb = 0;
                for (std::size_t o = 0; o < scene.objects.size(); ++o) ta += sa[r][o], tb += sb[r][o];
                std::printf("row %u at %.0f %.0f %.0f sums %.4f %.4f:", rr[r], c.x, c.y, c.z, ta, tb);
                for (std::size_t o = 0; o < scene.objects.size(); ++o) std::printf(" %+.2e", sb[r][o] - sa[r][o]);
                std::printf("\n");
            }
        }
        if (!fine_rows.empty()) {
            std::istringstream in(fine_rows);
            for (std::uint32_t r; in >> r;) fine[r] = true;
        }
        if (!fine_objects.empty()) {
            std::size_t nf = 0;
            for (std::uint32_t i = 0; i < scene.size(); ++i)
                if ((fine_objects + ",").find(scene.objects[scene.patches[i].object] + ",") != std::string::npos) fine[i] = true, ++nf;
            std::printf("fine rows: %zu of objects %s\n", nf, fine_objects.c_str());
        }
        SplitRowProvider both(own_light ? light.provider() : rest.provider(), rest.provider(), fine);
        const SolveResult r = solve_radiosity(scene, both, SolverOptions{});
        values.push_back(object_means(scene, r));
        std::printf("seed %llu: %llu shots, unshot %.2e, escaped / emitted %.4f%%\n", static_cast<unsigned long long>(seed),
                    static_cast<unsigned long long>(r.shots), r.unshot_fraction,
                    100 * luminance(r.energy.escaped) / luminance(r.energy.emitted));
        if (!f_light.empty()) continue;
        // The direct term, from the emitting rows: F_L,o = Σ_l A_l Σ_{j ∈ o} F_lj / Σ_l A_l, and the
        // direct luminance lum(ρ_o ⊙ Σ_l E_l A_l Σ_{j ∈ o} F_lj) / A_o (what B_o would be after the
        // light's first shot alone).
        const std::size_t no = scene.objects.size();
        std::vector<double> area(no, 0.0);
        std::vector<Vec3> power(no, Vec3(0.0)), kd(no, Vec3(0.0));
        for (std::size_t i = 0; i < scene.size(); ++i) {
            area[scene.patches[i].object] += scene.patches[i].area;
            kd[scene.patches[i].object] = scene.materials[scene.patches[i].material].kd;
        }
        f_light.assign(no, 0.0);
        direct.assign(no, 0.0);
        double light_area = 0;
        for (const auto& [l, row] : both.light_rows()) {
            const Patch& p = scene.patches[l];
            light_area += p.area;
            for (std::size_t e = 0; e < row.col.size(); ++e) {
                const std::uint32_t o = scene.patches[row.col[e]].object;
                f_light[o] += p.area * row.val[e];
                power[o] += p.area * row.val[e] * scene.materials[p.material].ke;
            }
        }
        for (std::size_t o = 0; o < no; ++o) {
            f_light[o] /= light_area;
            direct[o] = luminance(kd[o] * power[o]) / area[o];
        }
    }
    // Predicted noise of the direct term (ray caster): each emitting row's Σ_{j ∈ o} F_lj is a
    // binomial fraction of its M rays (stratifying the sender only lowers it), so over the n_L
    // emitting rows of equal power σ(F_L,o) / F_L,o = √((1 − F) / (F n_L M)), and the object's mean
    // moves by its direct share D_o / B_o times that. The other rows' noise averages over many
    // senders and is left to the seeds.
    const std::size_t k = values.size();
    std::printf("object,F_light,direct_share");
    if (rows.method == RowMethod::Raycast) std::printf(",predicted_direct_sigma_pct");
    for (std::uint64_t s : seeds) std::printf(",seed_%llu", static_cast<unsigned long long>(s));
    if (k > 1) std::printf(",mean,s_one_run_pct,s_mean_pct");
    std::printf("\n");
    for (std::size_t o = 0; o < scene.objects.size(); ++o) {
        const double share = direct[o] / values[0][o], f = f_light[o];
        std::printf("%s,%.5f,%.4f", scene.objects[o].c_str(), f, share);
        if (rows.method == RowMethod::Raycast)
            std::printf(",%.4f", f > 0 ? 100 * share * std::sqrt((1 - f) / (f * static_cast<double>(emitters * light_rays))) : 0.0);
        double m = 0;
        for (const auto& v : values) std::printf(",%.9g", v[o]), m += v[o] / static_cast<double>(k);
        if (k > 1) {
            double ss = 0;
            for (const auto& v : values) ss += (v[o] - m) * (v[o] - m);
            const double s = std::sqrt(ss / static_cast<double>(k - 1));
            std::printf(",%.9g,%.4f,%.4f", m, 100 * s / m, 100 * s / m / std::sqrt(static_cast<double>(k)));
        }
        std::printf("\n");
    }
    return 0;
} catch (const std::exception& e) {
    std::fprintf(stderr, "bench_reference_raycast: %s\n", e.what());
    return 1;
}
