// Cost of the near-field correction's far field (docs/accuracy.md, "Far field") against the
// hemicube row it corrects, in one run: per scene, the near analysis of every listed row with
// the far field off and on (one thread), and plain hemicube rows on one thread at resolution N.
// Prints µs per row for each and the far field's added cost as a share of a hemicube row: the
// budget near_field_options_for_hemicube() sets is 0.3 of a hemicube row by the cost model
// (column "estimated": NearFieldCorrector::far_field_cost_ns).
//
//   ./build/tools/bench_far_field [--rows R] [--resolution N] FILE.obj EDGE [FILE.obj EDGE ...]
//
// EDGE is --max-patch-edge. Rows are spread evenly over the patches (default 200 per scene).
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>
#include <utility>
#include <vector>

#include "ffcube/accuracy/near_field.hpp"
#include "ffcube/core/timer.hpp"
#include "ffcube/gl/hemicube_provider.hpp"
#include "ffcube/scene/mesher.hpp"
#include "ffcube/scene/obj_loader.hpp"

int main(int argc, char** argv) try {
    using namespace ffcube;
    std::size_t rows = 200;
    int resolution = 256;
    std::vector<std::pair<std::string, double>> scenes;
    for (int a = 1; a < argc; ++a) {
        if (!std::strcmp(argv[a], "--rows") && a + 1 < argc) rows = std::strtoul(argv[++a], nullptr, 10);
        else if (!std::strcmp(argv[a], "--resolution") && a + 1 < argc) resolution = std::atoi(argv[++a]);
        else if (a + 1 < argc) {
            scenes.emplace_back(argv[a], std::strtod(argv[a + 1], nullptr));
            ++a;
        } else {
            std::fprintf(stderr, "usage: bench_far_field [--rows R] [--resolution N] FILE.obj EDGE ...\n");
            return 2;
        }
    }
    std::printf("%-28s %7s %6s %12s %12s %12s %12s %12s %8s\n", "scene", "patches", "planes", "near µs/row",
                "far µs/row", "estimated", "ns/pair", "hemi µs/row", "far/hemi");
    for (const auto& [path, edge] : scenes) {
        MeshOptions mo;
        mo.max_patch_edge = edge;
        const Scene scene = build_scene(load_obj(path), mo);
        const std::size_t n = scene.size();
        const std::size_t r = std::min(rows, n);
        std::vector<std::uint32_t> list(r);
        for (std::size_t k = 0; k < r; ++k) list[k] = static_cast<std::uint32_t>(k * n / r);

        NearFieldOptions off = near_field_options_for_hemicube(resolution);
        off.far_field = NearFieldOptions::FarField::off;
        NearFieldOptions on = off;
        on.far_field = NearFieldOptions::FarField::automatic;
        on.far_field_budget_ns = INFINITY;  // on, with the cost estimate made
        double seconds[2] = {0, 0};
        std::size_t planes = 0;
        double estimate = NAN;
        for (int mode = 0; mode < 2; ++mode) {
            const NearFieldCorrector c(scene, mode ? on : off);
            if (mode) {
                planes = c.far_field_planes();
                estimate = c.far_field_cost_ns();
            }
            NearAnalysis a;
            NearFieldScratch scratch;  // as CorrectedRowProvider: buffers reused across rows
            Stopwatch watch;
            for (std::uint32_t i : list) c.analyse(i, a, scratch);
            seconds[mode] = watch.seconds();
        }
        HemicubeOptions ho;
        ho.resolution = resolution;
        ho.threads = 1;
        HemicubeRowProvider provider(scene, ho);
        Stopwatch watch;
        provider.compute_rows(list, [](std::uint32_t, const SparseRow&) {});
        const double hemi = watch.seconds();
        const double per_row = 1e6 / static_cast<double>(r);
        const double far = seconds[1] - seconds[0];
        std::printf("%-28s %7zu %6zu %12.1f %12.1f %12.1f %12.1f %12.1f %8.2f\n", path.c_str(), n, planes,
                    seconds[0] * per_row, far * per_row, estimate * 1e-3, 1e9 * far / static_cast<double>(r * n),
                    hemi * per_row, far / hemi);
        std::fflush(stdout);
    }
    return 0;
} catch (const std::exception& e) {
    std::fprintf(stderr, "bench_far_field: %s\n", e.what());
    return 1;
}
