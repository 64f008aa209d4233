// The reflections alone (solver/shortwave.hpp) on a stored F: steps per second for a batch of
// right-hand sides, by thread count; no item buffer, no files written (docs/benchmarks.md, "A
// day of shortwave"). The right-hand sides are deterministic pseudo-random incident powers on
// every patch (what matters for the cost is F, the step count and the sweeps).
//
//   ./build/tools/bench_shortwave_solve F.ffm [STEPS=48] [ALBEDO=0.3]
#include <fmt/format.h>

#include <chrono>
#include <ctime>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <thread>

#include "ffcube/io/ffm.hpp"
#include "ffcube/solver/shortwave.hpp"

int main(int argc, char** argv) {
    if (argc < 2) {
        std::fprintf(stderr, "usage: %s F.ffm [STEPS=48] [ALBEDO=0.3]\n", argv[0]);
        return 2;
    }
    const std::uint32_t steps = argc > 2 ? static_cast<std::uint32_t>(std::atoi(argv[2])) : 48;
    const double albedo = argc > 3 ? std::atof(argv[3]) : 0.3;
    const ffcube::FfmFile f = ffcube::read_ffm(argv[1]);
    const std::uint32_t n = f.matrix.size();
    const ffcube::ShortwaveSystem s = ffcube::make_shortwave_system(
        f.matrix, std::vector<double>(n, albedo), [](std::uint32_t i) { return fmt::format("patch {}", i); });
    std::vector<double> Q(std::size_t(n) * steps);
    for (std::size_t x = 0; x < Q.size(); ++x) Q[x] = 100.0 + static_cast<double>((x * 2654435761u) % 1000);
    fmt::print("{} patches, {} entries, {} steps, albedo {}, contraction {:.3f}\n", n, f.matrix.nnz(), steps, albedo,
               s.contraction);
    for (const unsigned threads : {1u, 2u}) {
        ffcube::ShortwaveControl c;
        c.threads = threads;
        const auto t0 = std::chrono::steady_clock::now();
        const std::clock_t c0 = std::clock();
        const ffcube::ShortwaveSolution x = ffcube::solve_shortwave(s, Q, steps, c);
        const double sec = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
        const double cpu = static_cast<double>(std::clock() - c0) / CLOCKS_PER_SEC;
        // On a shared machine the wall time depends on the load; the CPU time (all threads) does
        // much less: steps per CPU second × cores is what idle cores would give at best.
        fmt::print("threads {}: {:.3f} s wall ({:.1f} steps/s), {:.3f} s CPU ({:.1f} steps per CPU second), {} passes over F, "
                   "last change {:.2e}\n",
                   threads, sec, steps / sec, cpu, steps / cpu, x.iterations, x.change);
    }
    return 0;
}
