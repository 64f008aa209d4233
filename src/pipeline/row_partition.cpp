#include "ffcube/pipeline/row_partition.hpp"

#include <glm/geometric.hpp>

#include <algorithm>

#include "ffcube/core/error.hpp"

namespace ffcube {
namespace {

// Cost model constants, ns on one llvmpipe core (docs/benchmarks.md): a pixel of the atlas, a
// piece in front of the hemicube's plane (transform, face culling, its draw), a piece rejected
// by the plane test; a ray.
constexpr double kPixelNs = 5, kPieceFrontNs = 200, kPieceBehindNs = 10, kRayNs = 300;
constexpr std::size_t kMaxSamplePieces = 4096;

}  // namespace

std::vector<double> estimate_row_costs(const Scene& scene, const RowOptions& options) {
    const std::size_t n = scene.size();
    if (options.method == RowMethod::Raycast) return std::vector<double>(n, kRayNs * static_cast<double>(options.rays));
    const double pixels = 3.0 * options.resolution * options.resolution * kPixelNs;
    const std::size_t g = scene.grids.size();
    const std::size_t samples = std::min(g, kMaxSamplePieces);
    const double scale = samples > 0 ? static_cast<double>(g) / static_cast<double>(samples) : 0.0;
    std::vector<double> cost(n, pixels);
    // Every patch of a grid lies in the grid's plane, so the count is made once per grid.
    for (const PatchGrid& grid : scene.grids) {
        const std::uint32_t cells = grid.count == 4 ? grid.nu * grid.nv : grid.nu * grid.nu;
        if (cells == 0 || grid.first_patch >= n) continue;
        const Patch& p = scene.patches[grid.first_patch];
        std::size_t front = 0;
        for (std::size_t s = 0; s < samples; ++s) {
            const PatchGrid& other = scene.grids[s * g / samples];
            bool ahead = false;
            for (std::uint32_t c = 0; c < other.count && !ahead; ++c)
                ahead = glm::dot(other.corners[c] - p.centroid, p.normal) > 0.0;
            front += ahead ? 1 : 0;
        }
        const double pieces = scale * static_cast<double>(front);
        const double row = pixels + kPieceFrontNs * pieces + kPieceBehindNs * (static_cast<double>(g) - pieces);
        const std::size_t last = std::min<std::size_t>(n, std::size_t(grid.first_patch) + cells);
        std::fill(cost.begin() + grid.first_patch, cost.begin() + static_cast<std::ptrdiff_t>(last), row);
    }
    return cost;
}

std::vector<std::uint32_t> balanced_row_blocks(std::span<const double> cost, unsigned parts) {
    FFCUBE_CHECK(parts >= 1);
    const auto n = static_cast<std::uint32_t>(cost.size());
    double total = 0;
    for (double c : cost) total += c;
    std::vector<std::uint32_t> bounds(parts + 1, n);
    bounds[0] = 0;
    double running = 0;
    std::uint32_t i = 0;
    for (unsigned r = 1; r < parts; ++r) {
        const double target = total * r / parts;
        while (i < n && running + cost[i] / 2 < target) running += cost[i++];  // row i goes where most of it is
        bounds[r] = i;
    }
    return bounds;
}

}  // namespace ffcube
