// The direct beam of a day alone (gl/sun.hpp): shadow polygons (sunlit_fractions_clipped) per
// step, wall and CPU time, for 1 and 2 threads; with a pixel budget given, also the item buffer at
// that budget and the fractions' differences |f_pixels − f_clip| (mean and max over lit patches)
// (docs/benchmarks.md, "A day of shortwave"). The suns are those of tools/bench_shortwave.py's
// day (96 quarter hours, elevation up to 60°), those above the horizon.
//
//   ./build/tools/bench_sun CITY.stl [STEPS=96] [MAX_PIXELS=0: no item buffer]
#include <fmt/format.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <ctime>
#include <numbers>

#include "ffcube/gl/sun.hpp"
#include "ffcube/io/report.hpp"
#include "ffcube/pipeline/scene_loading.hpp"

namespace {
double now() { return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count(); }
double cpu() {
    timespec t{};
    clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &t);
    return static_cast<double>(t.tv_sec) + 1e-9 * static_cast<double>(t.tv_nsec);
}
}  // namespace

int main(int argc, char** argv) {
    if (argc < 2) {
        std::fprintf(stderr, "usage: %s CITY.stl [STEPS=96] [MAX_PIXELS=0]\n", argv[0]);
        return 2;
    }
    const int steps = argc > 2 ? std::atoi(argv[2]) : 96;
    const unsigned long long budget = argc > 3 ? std::strtoull(argv[3], nullptr, 10) : 0;
    ffcube::SceneOptions so;
    so.path = argv[1];
    so.subdivide = false;
    ffcube::Report report;
    const ffcube::Scene scene = ffcube::load_and_mesh(so, report);
    std::vector<ffcube::Vec3> suns;
    for (int k = 0; k < steps; ++k) {
        const double h = 24.0 * k / steps, el = 60.0 * std::sin(std::numbers::pi * (h - 6.0) / 12.0);
        const double az = std::fmod(180.0 + 15.0 * (h - 12.0) + 360.0, 360.0);
        if (el > 0) suns.push_back(ffcube::sun_direction_from_angles(az, el));
    }
    fmt::print("{} patches, {} suns above the horizon of {} steps\n", scene.size(), suns.size(), steps);
    const auto count_of = static_cast<double>(suns.size());
    std::vector<ffcube::SunResult> clip;
    for (const unsigned threads : {1u, 2u}) {
        clip.clear();
        const double w0 = now(), c0 = cpu();
        for (const ffcube::Vec3& s : suns) clip.push_back(ffcube::sunlit_fractions_clipped(scene, s, threads));
        const double wall = now() - w0, used = cpu() - c0;
        fmt::print("clip, threads {}: {:.3f} s wall ({:.1f} steps/s, {:.1f} ms a step), {:.3f} s CPU ({:.1f} steps per CPU second)\n",
                   threads, wall, count_of / wall, 1e3 * wall / count_of, used, count_of / used);
    }
    if (budget == 0) return 0;
    ffcube::SunOptions o;
    o.max_pixels = budget;
    std::unique_ptr<ffcube::GlContext> ctx = ffcube::create_headless_context(o.backend);
    double sum = 0.0, worst = 0.0, wall = 0.0;
    std::size_t count = 0;
    for (std::size_t k = 0; k < suns.size(); ++k) {
        const ffcube::SunResult p = ffcube::sunlit_fractions(scene, suns[k], o, *ctx);
        wall += p.seconds;
        for (std::size_t i = 0; i < scene.size(); ++i) {
            if (!(clip[k].cosine[i] > 1e-9)) continue;
            const double d = std::abs(p.fraction[i] - clip[k].fraction[i]);
            sum += d;
            worst = std::max(worst, d);
            ++count;
        }
        if (k == 0)
            fmt::print("pixels {}: pixel {:.4g}, setup {:.3f} s, project {:.3f}, draw {:.3f}, readback {:.3f}, count {:.3f}\n", budget,
                       p.pixel_size, p.seconds_setup, p.seconds_project, p.seconds_draw, p.seconds_readback, p.seconds_count);
    }
    fmt::print("pixels {}: {:.3f} s wall ({:.2f} s a step); |f_pixels - f_clip| over {} lit fractions: mean {:.3g}, max {:.3g}\n",
               budget, wall, wall / count_of, count, sum / static_cast<double>(count), worst);
    return 0;
}
