// Where the floor's bias on a mixed-size mesh comes from (issue 16; docs/adaptive.md, "The floor's
// bias on a mixed-size mesh"). On the default mesh of the built-in Cornell box (--patches 2000,
// contact cuts auto) it solves:
//   coarse    the default mesh;
//   fine      every patch split S × S (refine_patches), a mesh nested in the coarse one, so that
//             each coarse patch's fine mean is exact (no point-in-polygon guessing);
//   adaptive  one adaptive level (target 1e-3, budget 2700: what `ffcube solve --patches 2000
//             --target-error 1e-3 --max-elements 2700` does);
//   random    the same number of floor patches as adaptive split, chosen at random (seeded), only
//             on the floor, each 2 × 2: mixed sizes without the estimator's choice;
//   on/off    adaptive's choice of patches to split restricted to the floor, and to every object
//             but the floor (plain solves: every row measured, as --no-reuse-rows);
// and prints each object's mean luminance in each run against the fine run's, and for the floor
// (or OBJECT), per coarse patch i, the signed sums of A_i (x_i − y_i) / Σ A B_fine over the
// patches adaptive split and over the rest, x and y the means over patch i of two runs (for
// "coarse − fine" that is the coarse mesh's error by region against its nested refinement).
//
//   ./build/tools/bench_floor_bias [--resolution N] [--threads T] [--fine S] [--seed K] [--object NAME]
//                                  [--budget N] [--method hemicube|raycast] [--correct near|none]
//
// Luminance is 0.2126 r + 0.7152 g + 0.0722 b, as tools/bench_adaptive.sh computes errors.
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <algorithm>
#include <random>
#include <string>
#include <utility>
#include <vector>

#include <fmt/format.h>

#include "ffcube/io/report.hpp"
#include "ffcube/pipeline/adaptive.hpp"
#include "ffcube/pipeline/options.hpp"
#include "ffcube/pipeline/row_source.hpp"
#include "ffcube/pipeline/scene_loading.hpp"
#include "ffcube/scene/refine.hpp"
#include "ffcube/solver/solver.hpp"

namespace {

using namespace ffcube;

double luminance(const Vec3& b) { return 0.2126 * b.r + 0.7152 * b.g + 0.0722 * b.b; }

double escaped_share(const SolveResult& r) { return luminance(r.energy.escaped) / luminance(r.energy.emitted); }

// A run on a refinement of the coarse scene: per coarse patch, the area and the Σ A B of its elements.
struct PerCoarse {
    std::vector<double> area, power;
    double escaped = 0;  // the luminance of the power escaped (the open front) over the emitted
    double mean(std::size_t i) const { return power[i] / area[i]; }
};

PerCoarse per_coarse(const Scene& scene, const SolveResult& solved, const std::vector<std::uint32_t>& origin,
                     std::size_t coarse_patches) {
    PerCoarse p{std::vector<double>(coarse_patches, 0.0), std::vector<double>(coarse_patches, 0.0), escaped_share(solved)};
    for (std::size_t e = 0; e < scene.size(); ++e) {
        p.area[origin[e]] += scene.patches[e].area;
        p.power[origin[e]] += scene.patches[e].area * luminance(solved.radiosity[e]);
    }
    return p;
}

SolveResult solve(const Scene& scene, const RowOptions& rows) {
    RowSource source = make_row_source(scene, rows);
    return solve_radiosity(scene, source.provider(), SolverOptions{});
}

// The coarse scene with patch i split split[i] × split[i], solved, per coarse patch.
PerCoarse solve_split(const Scene& coarse, const std::vector<std::uint32_t>& split, const RowOptions& rows) {
    const RefinedScene r = refine_patches(coarse, split);
    return per_coarse(r.scene, solve(r.scene, rows), r.parent, coarse.size());
}

struct Sums {
    double split = 0, rest = 0;
};

// Σ over the object's coarse patches of A_i (value_i − reference_i), split by `marked`, over `total`.
Sums signed_sums(const Scene& coarse, std::uint32_t object, const std::vector<bool>& marked, const PerCoarse& value,
                 const PerCoarse& reference, double total) {
    Sums s;
    for (std::size_t i = 0; i < coarse.size(); ++i) {
        if (coarse.patches[i].object != object) continue;
        const double d = coarse.patches[i].area * (value.mean(i) - reference.mean(i)) / total;
        (marked[i] ? s.split : s.rest) += d;
    }
    return s;
}

double object_mean(const Scene& coarse, std::uint32_t object, const PerCoarse& run) {
    double a = 0, p = 0;
    for (std::size_t i = 0; i < coarse.size(); ++i)
        if (coarse.patches[i].object == object) a += run.area[i], p += run.power[i];
    return p / a;
}

}  // namespace

int main(int argc, char** argv) try {
    RowOptions rows;
    rows.threads = 1;
    std::uint32_t fine_split = 2;
    bool localise = false;
    std::size_t budget = 2700;
    unsigned seed = 1;
    std::string object_name = "floor";
    for (int a = 1; a + 1 < argc; a += 2) {
        const std::string k = argv[a], v = argv[a + 1];
        if (k == "--resolution") rows.resolution = std::atoi(v.c_str());
        else if (k == "--threads") rows.threads = static_cast<unsigned>(std::atoi(v.c_str()));
        else if (k == "--localise") localise = v == "1";
        else if (k == "--fine") fine_split = static_cast<std::uint32_t>(std::atoi(v.c_str()));
        else if (k == "--seed") seed = static_cast<unsigned>(std::atoi(v.c_str()));
        else if (k == "--object") object_name = v;
        else if (k == "--budget") budget = std::strtoul(v.c_str(), nullptr, 10);
        else if (k == "--method") rows.method = parse_row_method(v);
        else if (k == "--correct") rows.correct = parse_correction(v);
        else {
            std::fprintf(stderr, "bench_floor_bias: unknown option %s (see the comment at the top of tools/bench_floor_bias.cpp)\n", k.c_str());
            return 2;
        }
    }
    if (argc % 2 == 0 || fine_split < 2) {
        std::fprintf(stderr, "bench_floor_bias: options come in pairs and --fine is at least 2 (see the comment at the top of "
                             "tools/bench_floor_bias.cpp)\n");
        return 2;
    }
    SceneOptions so;
    so.patches = 2000;
    Report report;
    const Scene coarse = load_and_mesh(so, report);
    std::uint32_t object = 0;
    while (object < coarse.objects.size() && coarse.objects[object] != object_name) ++object;
    if (object == coarse.objects.size()) {
        std::fprintf(stderr, "bench_floor_bias: no object named %s in the Cornell box\n", object_name.c_str());
        return 2;
    }
    const std::size_t n = coarse.size();
    std::vector<std::uint32_t> identity(n);
    for (std::uint32_t i = 0; i < n; ++i) identity[i] = i;

    const PerCoarse c = per_coarse(coarse, solve(coarse, rows), identity, n);
    // The reference: the nested fine mesh, or with --localise 1 the coarse run itself (no fine solve).
    const PerCoarse f = localise ? c : solve_split(coarse, std::vector<std::uint32_t>(n, fine_split), rows);

    AdaptiveOptions ao;
    ao.max_elements = budget;
    ao.max_levels = 1;
    const AdaptiveResult ad = solve_adaptive(coarse, rows, SolverOptions{}, ao);
    const PerCoarse a = per_coarse(*ad.scene, ad.result, ad.origin, n);
    std::vector<bool> split(n, false);
    std::vector<std::uint32_t> on_object;
    std::vector<std::size_t> children(n, 0);
    for (std::uint32_t o : ad.origin) ++children[o];
    std::size_t split_on_object = 0;
    for (std::uint32_t i = 0; i < n; ++i) {
        split[i] = children[i] > 1;
        if (coarse.patches[i].object != object) continue;
        on_object.push_back(i);
        split_on_object += split[i];
    }

    // A split of the coarse mesh, solved, with the patches it splits.
    struct Run {
        std::string name;
        PerCoarse result;
        std::vector<bool> marked;
    };
    std::vector<Run> runs;
    const auto add_run = [&](std::string name, const std::vector<std::uint32_t>& factors) {
        std::vector<bool> marked(n);
        for (std::uint32_t i = 0; i < n; ++i) marked[i] = factors[i] > 1;
        runs.push_back({std::move(name), solve_split(coarse, factors, rows), std::move(marked)});
    };
    // Adaptive's choice restricted to the patches `keep` accepts (plain solves: every row measured,
    // as --no-reuse-rows).
    const auto choice_where = [&](const auto& keep) {
        std::vector<std::uint32_t> factors(n, 1);
        for (std::uint32_t i = 0; i < n; ++i)
            if (split[i] && keep(coarse.objects[coarse.patches[i].object])) factors[i] = ao.factor;
        return factors;
    };
    // `count` patches that `keep` accepts, chosen at random (seeded), each split by adaptive's factor.
    std::mt19937 rng(seed);
    const auto random_where = [&](const auto& keep, std::size_t count) {
        std::vector<std::uint32_t> pool, factors(n, 1);
        for (std::uint32_t i = 0; i < n; ++i)
            if (keep(coarse.objects[coarse.patches[i].object])) pool.push_back(i);
        std::shuffle(pool.begin(), pool.end(), rng);
        for (std::size_t k = 0; k < std::min(count, pool.size()); ++k) factors[pool[k]] = ao.factor;
        return factors;
    };
    const auto is_object = [&](const std::string& o) { return o == object_name; };
    const auto not_object = [&](const std::string& o) { return o != object_name; };
    if (!localise) {
        add_run("adaptive's choice on the object only", choice_where(is_object));
        add_run("adaptive's choice off the object", choice_where(not_object));
        add_run("random split on the object", random_where(is_object, split_on_object));
    } else {
        std::size_t split_off_object = 0;
        for (std::uint32_t i = 0; i < n; ++i) split_off_object += split[i] && coarse.patches[i].object != object;
        add_run("adaptive's choice on the blocks only",
                choice_where([](const std::string& o) { return o.find("block") != std::string::npos; }));
        add_run("adaptive's choice on the walls and ceiling only", choice_where([&](const std::string& o) {
                    return o != object_name && o != "light" && o.find("block") == std::string::npos;
                }));
        add_run("random split off the object (as many as adaptive's choice there)", random_where(not_object, split_off_object));
    }

    std::vector<std::size_t> split_per_object(coarse.objects.size(), 0);
    for (std::uint32_t i = 0; i < n; ++i) split_per_object[coarse.patches[i].object] += split[i];
    double total = 0;  // Σ A B of the reference run over the object
    for (std::uint32_t i : on_object) total += f.power[i];
    std::printf("%s: %zu of its %zu patches split by adaptive (%zu elements in all), resolution %d, reference %s\n",
                object_name.c_str(), split_on_object, on_object.size(), ad.scene->size(), rows.resolution,
                localise ? "coarse" : fmt::format("fine {} x {}", fine_split, fine_split).c_str());
    std::printf("patches adaptive split, per object:");
    for (std::uint32_t o = 0; o < coarse.objects.size(); ++o) std::printf(" %s %zu", coarse.objects[o].c_str(), split_per_object[o]);
    std::printf("\n\n| run, mean luminance against the reference |");
    for (const std::string& o : coarse.objects) std::printf(" %s |", o.c_str());
    std::printf(" escaped / emitted |\n|---|");
    for (std::size_t o = 0; o <= coarse.objects.size(); ++o) std::printf("---|");
    std::printf("\n");
    const auto object_row = [&](const std::string& name, const PerCoarse& run) {
        std::printf("| %s |", name.c_str());
        for (std::uint32_t o = 0; o < coarse.objects.size(); ++o)
            std::printf(" %+.3f%% |", 100 * (object_mean(coarse, o, run) / object_mean(coarse, o, f) - 1));
        std::printf(" %.4f%% |\n", 100 * run.escaped);
    };
    if (!localise) object_row(fmt::format("fine {} x {} (the reference)", fine_split, fine_split), f);
    object_row("coarse", c);
    object_row("adaptive", a);
    for (const Run& r : runs) object_row(r.name, r.result);
    std::printf("\n| on %s, sum of A_i (x_i - y_i) / sum A B_ref | on the patches split | on the rest | total |\n|---|---|---|---|\n",
                object_name.c_str());
    const auto row = [](const std::string& name, const Sums& s) {
        std::printf("| %s | %+.3f%% | %+.3f%% | %+.3f%% |\n", name.c_str(), 100 * s.split, 100 * s.rest, 100 * (s.split + s.rest));
    };
    if (!localise) row("coarse - fine", signed_sums(coarse, object, split, c, f, total));
    row("adaptive - coarse", signed_sums(coarse, object, split, a, c, total));
    for (const Run& r : runs) row(r.name + " - coarse (its own split set)", signed_sums(coarse, object, r.marked, r.result, c, total));
    return 0;
} catch (const std::exception& e) {
    std::fprintf(stderr, "bench_floor_bias: %s\n", e.what());
    return 1;
}
