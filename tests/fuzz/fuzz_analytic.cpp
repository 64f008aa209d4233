// libFuzzer target: the analytic polygon-to-polygon form factor on pairs decoded from the input
// bytes, through the same biased generator as the property test
// (tests/geometry/analytic_pairs.hpp: shared edges and vertices, near-collinear edges, slivers,
// 1e-12 gaps, 1e5 offsets, 1e-6 scales, 1e-4 size ratios, touching perpendicular pairs). The
// bytes are read 4 at a time as uniform draws; once they run out, a SplitMix64 stream seeded
// by their hash continues, so every input decodes to a complete, deterministic pair.
// Checked for each pair, both directions: the value is finite and in [0, 1 + stated error]; the
// evaluations stay within ff_polygon_polygon_budget of the vertex counts (+1 each for clipping a
// convex polygon); reciprocity A1 F12 = A2 F21 holds within the sum of both directions' stated
// errors (stated_error_area, derived in analytic_pairs.hpp, the property test's bound). Only an
// exactly zero-area polygon may be refused (InputError). A violation aborts (libFuzzer keeps the
// input).
#include "../geometry/analytic_pairs.hpp"

#include "ffcube/core/error.hpp"
#include "ffcube/geometry/analytic.hpp"

#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>

namespace {

struct ByteSource {
    const std::uint8_t* data;
    std::size_t size, pos = 0;
    std::uint64_t state;
    double operator()() {
        std::uint32_t v = 0;
        if (pos + 4 <= size) {
            std::memcpy(&v, data + pos, 4);
            pos += 4;
        } else {
            // SplitMix64 (Steele, Lea, Flood 2014).
            std::uint64_t z = (state += 0x9e3779b97f4a7c15ULL);
            z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ULL;
            z = (z ^ (z >> 27)) * 0x94d049bb133111ebULL;
            v = static_cast<std::uint32_t>((z ^ (z >> 31)) >> 32);
        }
        return static_cast<double>(v) * 0x1.0p-32;
    }
};

[[noreturn]] void fail(const char* what, double a, double b) {
    std::fprintf(stderr, "fuzz_analytic: %s (%.17g, %.17g)\n", what, a, b);
    std::abort();
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    std::uint64_t hash = 1469598103934665603ULL;  // FNV-1a
    for (std::size_t i = 0; i < size; ++i) hash = (hash ^ data[i]) * 1099511628211ULL;
    ByteSource src{data, size, 0, hash};
    ffcube::testing::PairGenerator<ByteSource> gen(src);
    const ffcube::testing::PolygonPair p = gen.next();
    using ffcube::polygon_area;
    ffcube::AnalyticCallInfo i12, i21;
    double f12 = 0, f21 = 0;
    try {
        f12 = ffcube::ff_polygon_polygon(p.p1, p.p2, i12);
        f21 = ffcube::ff_polygon_polygon(p.p2, p.p1, i21);
    } catch (const ffcube::InputError&) {
        if (polygon_area(p.p1) == 0.0 || polygon_area(p.p2) == 0.0) return 0;
        fail("a pair with non-zero areas was refused", polygon_area(p.p1), polygon_area(p.p2));
    }
    if (!std::isfinite(f12) || !std::isfinite(f21)) fail("non-finite form factor", f12, f21);
    const double e12 = ffcube::testing::stated_error_area(p.p1, p.p2, f12, i12);
    const double e21 = ffcube::testing::stated_error_area(p.p2, p.p1, f21, i21);
    const std::size_t n1 = p.p1.size() + 1, n2 = p.p2.size() + 1;  // convex: clipping adds ≤ 1
    if (i12.evaluations > ffcube::ff_polygon_polygon_budget(n1, n2))
        fail("evaluation budget exceeded", static_cast<double>(i12.evaluations), 0);
    if (i21.evaluations > ffcube::ff_polygon_polygon_budget(n2, n1))
        fail("evaluation budget exceeded", static_cast<double>(i21.evaluations), 1);
    const double s = std::max(ffcube::polygon_max_edge(p.p1), ffcube::polygon_max_edge(p.p2));
    const double a1 = polygon_area(p.p1) / (s * s), a2 = polygon_area(p.p2) / (s * s);
    if (f12 < 0 || f21 < 0 || f12 > 1 + e12 / a1 || f21 > 1 + e21 / a2) fail("form factor outside [0, 1]", f12, f21);
    if (std::abs(a1 * f12 - a2 * f21) > e12 + e21) fail("reciprocity A1 F12 = A2 F21 broken", a1 * f12, a2 * f21);
    return 0;
}
