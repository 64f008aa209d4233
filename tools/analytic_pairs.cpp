// Prints random polygon pairs of the analytic property test's generator
// (tests/geometry/analytic_pairs.hpp) with ffcube's values, for an independent reference:
//   ./build/tools/analytic_pairs --count 40 --kinds hinged,stress --seed 1 > pairs.txt
//   python3 tools/analytic_reference.py --pairs pairs.txt
// Per pair: "pair K KIND", the two polygons ("poly:" then one "x y z" per line), and
// "ffcube A1F12 A2F21 BOUND12 BOUND21": ffcube's A·F both ways and the errors it states for them
// (stated_error_area, in the same absolute units). The property test has closed-form references
// for the other kinds; hinged and stress pairs have none but this one.
#include "../tests/geometry/analytic_pairs.hpp"

#include "ffcube/core/error.hpp"
#include "ffcube/geometry/analytic.hpp"

#include <cstdio>
#include <cstdlib>
#include <random>
#include <set>
#include <sstream>
#include <string>

int main(int argc, char** argv) {
    using namespace ffcube;
    int count = 40;
    std::uint64_t seed = 1;
    std::set<testing::PairKind> kinds = {testing::PairKind::hinged, testing::PairKind::stress};
    for (int i = 1; i < argc; ++i) {
        const std::string a = argv[i];
        if (a == "--count" && i + 1 < argc) {
            count = std::atoi(argv[++i]);
        } else if (a == "--seed" && i + 1 < argc) {
            seed = std::strtoull(argv[++i], nullptr, 10);
        } else if (a == "--kinds" && i + 1 < argc) {
            kinds.clear();
            std::stringstream list(argv[++i]);
            std::string word;
            while (std::getline(list, word, ',')) {
                bool found = false;
                for (int k = 0; k < static_cast<int>(testing::PairKind::count); ++k) {
                    const auto kind = static_cast<testing::PairKind>(k);
                    if (word == testing::kind_name(kind)) {
                        kinds.insert(kind);
                        found = true;
                    }
                }
                if (!found) {
                    std::fprintf(stderr, "analytic_pairs: unknown kind '%s'\n", word.c_str());
                    return 2;
                }
            }
        } else {
            std::fprintf(stderr, "usage: analytic_pairs [--count N] [--seed S] [--kinds k1,k2,...]\n");
            return 2;
        }
    }
    std::mt19937_64 rng(seed);
    std::uniform_real_distribution<double> u(0.0, 1.0);
    auto source = [&] { return u(rng); };
    testing::PairGenerator<decltype(source)> gen(source);
    for (int k = 0; k < count;) {
        const testing::PolygonPair p = gen.next();
        if (!kinds.count(p.kind)) continue;
        AnalyticCallInfo i12, i21;
        double f12 = 0, f21 = 0;
        try {
            f12 = ff_polygon_polygon(p.p1, p.p2, i12);
            f21 = ff_polygon_polygon(p.p2, p.p1, i21);
        } catch (const InputError&) {
            continue;  // a polygon of zero area after rounding: nothing to compare
        }
        const double s = std::max(polygon_max_edge(p.p1), polygon_max_edge(p.p2));
        std::printf("pair %d %s\n", k, testing::kind_name(p.kind));
        for (const auto* poly : {&p.p1, &p.p2}) {
            std::printf("poly:\n");
            for (const Vec3& v : *poly) std::printf("%.17g %.17g %.17g\n", v.x, v.y, v.z);
        }
        std::printf("ffcube %.17g %.17g %.17g %.17g\n", polygon_area(p.p1) * f12, polygon_area(p.p2) * f21,
                    testing::stated_error_area(p.p1, p.p2, f12, i12) * s * s,
                    testing::stated_error_area(p.p2, p.p1, f21, i21) * s * s);
        ++k;
    }
}
