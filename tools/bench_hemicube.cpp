// Hemicube throughput on the built-in Cornell box (or a scene file, one patch per face): hemicubes/s
// and the share of time in preparing (CPU transform and culling), drawing, readback and
// accumulation, for each resolution, thread count and occlusion setting, and the pieces drawn
// and left out by occlusion per hemicube. Whole rows are computed exactly as `ffcube formfactors
// --correct none` does.
//
//   ./build/tools/bench_hemicube [--patches 5000] [--resolutions 64,128,256,512] [--threads 1,2]
//                                [--rows R] [--backend auto|egl|osmesa] [--scene FILE]
//                                [--occlusion 1,0]
//
// --rows limits how many rows are computed per setting (spread evenly over the patches).
// --scene: a scene file meshed with --no-subdivide (e.g. a city of tools/gen_city.py).
// --occlusion: HemicubeOptions::occlusion_culling, 1 on (the default), 0 off.
// Compare settings as ratios within one run: these machines are shared and noisy.
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <sstream>
#include <string>
#include <vector>

#include "ffcube/core/timer.hpp"
#include "ffcube/gl/hemicube_provider.hpp"
#include "ffcube/io/report.hpp"
#include "ffcube/pipeline/scene_loading.hpp"
#include "ffcube/scene/builtin.hpp"
#include "ffcube/scene/mesher.hpp"

namespace {
std::vector<int> parse_list(const char* s) {
    std::vector<int> v;
    std::stringstream ss(s);
    std::string item;
    while (std::getline(ss, item, ',')) v.push_back(std::atoi(item.c_str()));
    return v;
}
}  // namespace

int main(int argc, char** argv) try {
    using namespace ffcube;
    std::size_t patches = 5000, rows = 0;
    std::vector<int> resolutions = {64, 128, 256, 512}, threads = {1, 2}, occlusion = {1};
    std::string scene_file;
    Backend backend = Backend::Auto;
    for (int a = 1; a + 1 < argc; a += 2) {
        if (!std::strcmp(argv[a], "--patches")) patches = std::strtoul(argv[a + 1], nullptr, 10);
        else if (!std::strcmp(argv[a], "--resolutions")) resolutions = parse_list(argv[a + 1]);
        else if (!std::strcmp(argv[a], "--threads")) threads = parse_list(argv[a + 1]);
        else if (!std::strcmp(argv[a], "--rows")) rows = std::strtoul(argv[a + 1], nullptr, 10);
        else if (!std::strcmp(argv[a], "--backend")) backend = parse_backend(argv[a + 1]);
        else if (!std::strcmp(argv[a], "--scene")) scene_file = argv[a + 1];
        else if (!std::strcmp(argv[a], "--occlusion")) occlusion = parse_list(argv[a + 1]);
        else {
            std::fprintf(stderr, "unknown option %s\n", argv[a]);
            return 2;
        }
    }
    Scene scene;
    if (scene_file.empty()) {
        MeshOptions mo;
        mo.target_patches = patches;
        scene = build_scene(load_cornell_box(), mo);
    } else {
        SceneOptions so;
        so.path = scene_file;
        so.subdivide = false;
        Report ignored;
        scene = load_and_mesh(so, ignored);
    }
    const std::size_t n = scene.size();
    if (rows == 0 || rows > n) rows = n;
    std::vector<std::uint32_t> list(rows);
    for (std::size_t k = 0; k < rows; ++k) list[k] = static_cast<std::uint32_t>(k * n / rows);
    std::printf("%s, %zu patches, %zu rows per setting\n", scene_file.empty() ? "Cornell box" : scene_file.c_str(), n,
                rows);
    std::printf("%6s %7s %5s %12s %9s %9s %9s %9s %10s %9s %9s\n", "N", "threads", "occl", "hemicubes/s", "prepare",
                "draw", "readback", "accum", "vs 1 thr", "drawn/h", "occl/h");
    for (int res : resolutions) {
      for (int occl : occlusion) {
        double base = 0;
        for (int t : threads) {
            HemicubeOptions opt;
            opt.resolution = res;
            opt.threads = static_cast<unsigned>(t);
            opt.backend = backend;
            opt.occlusion_culling = occl != 0;
            HemicubeRowProvider provider(scene, opt);
            Stopwatch watch;
            provider.compute_rows(list, [](std::uint32_t, const SparseRow&) {});
            const double secs = watch.seconds();
            const HemicubeStats st = provider.stats();
            const double total = st.prepare_seconds + st.draw_seconds + st.readback_seconds + st.accumulate_seconds;
            const double rate = static_cast<double>(rows) / secs;
            if (base == 0) base = rate;
            std::uint64_t drawn = 0, occluded = 0;
            for (std::size_t f = 0; f < 5; ++f) {
                drawn += st.pieces_drawn[f];
                occluded += st.pieces_occluded[f];
            }
            const double h = st.hemicubes ? static_cast<double>(st.hemicubes) : 1.0;
            std::printf("%6d %7d %5d %12.0f %8.1f%% %8.1f%% %8.1f%% %8.1f%% %9.2fx %9.0f %9.0f\n", res, t, occl, rate,
                        100 * st.prepare_seconds / total, 100 * st.draw_seconds / total,
                        100 * st.readback_seconds / total, 100 * st.accumulate_seconds / total, rate / base,
                        static_cast<double>(drawn) / h, static_cast<double>(occluded) / h);
            std::fflush(stdout);
        }
      }
    }
    return 0;
} catch (const std::exception& e) {
    std::fprintf(stderr, "bench_hemicube: %s\n", e.what());
    return 1;
}
