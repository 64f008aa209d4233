// The far field's cost model: its cost per row, estimated from the geometry of a sample of rows,
// which decides whether `--far-field auto` turns it on (docs/accuracy.md, "When it is on").
#include <glm/geometric.hpp>

#include <algorithm>
#include <bit>

#include "accuracy/far_field.hpp"
#include "accuracy/shaft_test.hpp"

namespace ffcube::accuracy {

namespace {

// Cost model of the far field on one core (ns), calibrated with tools/bench_far_field on these
// machines (docs/benchmarks.md): per candidate patch (distance, facing and plane tests), and per
// entry by its rule: 9 Lambert contours, 81, 16 or 1 kernel evaluations; per plane whose section
// by the pair's hull must be examined (or is rejected at once: the pair's box misses the
// plane's members).
constexpr double kCostCandidate = 12, kCostLambert3 = 1000, kCostPoint3 = 250, kCostPoint2 = 50, kCostPoint1 = 7,
                 kCostSection = 100, kCostSectionReject = 5;
constexpr std::size_t kCostSampleRows = 64;

}  // namespace

double far_field_cost_floor_ns(std::size_t patches) { return kCostCandidate * static_cast<double>(patches); }

// The far field's cost per row, estimated from up to kCostSampleRows rows spread over the scene:
// for each, the facing pairs beyond the near range by rule (visibility assumed proven: an upper
// bound), and whether the row would be complete (every near pair proven by the shaft test and
// every far one by the plane test: not rendered at all). Deterministic: a function of the
// geometry only.
double FarField::estimate_cost(double& complete_fraction) const {
    const Scene& scene = patches_.scene;
    const std::size_t n = scene.size();
    const std::size_t rows = std::min(n, kCostSampleRows);
    ShaftScratch shaft;
    double total = 0;
    std::size_t complete = 0;
    for (std::size_t r = 0; r < rows; ++r) {
        const auto i = static_cast<std::uint32_t>(r * n / rows);
        const Patch& pi = scene.patches[i];
        double cost = kCostCandidate * static_cast<double>(n);
        bool known = true;  // every facing pair proven: the row would not be rendered
        for (std::uint32_t j = 0; j < n; ++j) {
            if (j == i) continue;
            const Patch& pj = scene.patches[j];
            const double size = std::max(pi.size, pj.size);
            const double d = glm::length(pj.centroid - pi.centroid);
            if (!patches_.facing(i, j)) continue;
            if (d < options_.k * size) {
                if (known) known = shaft_unoccluded(patches_, grid_, i, j, shaft);
                continue;
            }
            const Box pair = patches_.pair_box(i, j);
            for (std::size_t w = 0; w < words_; ++w) {
                std::uint64_t c = (plus_bits_[i * words_ + w] | plus_bits_[j * words_ + w]) &
                                  (minus_bits_[i * words_ + w] | minus_bits_[j * words_ + w]);
                for (; c; c &= c - 1)
                    cost += pair.overlaps(planes_[w * 64 + static_cast<std::size_t>(std::countr_zero(c))].box)
                                ? kCostSection
                                : kCostSectionReject;
            }
            cost += d < kFarPoint3K * size   ? kCostLambert3
                    : d < kFarPoint2K * size ? kCostPoint3
                    : d < kFarPoint1K * size ? kCostPoint2
                                             : kCostPoint1;
            if (known) known = unoccluded(i, j);
        }
        total += cost;
        complete += known;
    }
    complete_fraction = static_cast<double>(complete) / static_cast<double>(rows);
    return total / static_cast<double>(rows);
}

}  // namespace ffcube::accuracy
