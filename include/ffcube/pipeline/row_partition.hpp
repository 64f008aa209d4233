// Splitting the rows of F into contiguous blocks of about equal estimated cost: how the ranks of
// `mpirun … ffcube` share the work (src/mpi, docs/scaling.md). Pure functions of the scene and
// the options, so every rank (and every rerun, for resuming) gets the same blocks.
#pragma once

#include <cstdint>
#include <span>
#include <vector>

#include "ffcube/pipeline/options.hpp"
#include "ffcube/scene/scene.hpp"

namespace ffcube {

// Estimated cost of each row (ns on one core of llvmpipe; only the ratios matter). A hemicube row
// costs its pixels (3N² at about 5 ns, docs/benchmarks.md) plus the pieces (Scene::grids) it has
// to transform and cull, about 200 ns each for the pieces with a corner in front of the row's
// plane (the rest are rejected by one test, counted at 10 ns): a patch facing the whole scene
// costs more than one looking at a wall. A ray-cast row costs its rays, the same for every row.
// Pieces are tested against at most 4096 pieces spread over the scene (scaled up), so the
// estimate costs O(grids × 4096), not O(grids²).
std::vector<double> estimate_row_costs(const Scene& scene, const RowOptions& options);

// Bounds of `parts` contiguous blocks: block r is rows [bounds[r], bounds[r+1]), bounds[0] = 0,
// bounds[parts] = cost.size(), each block's summed cost as close to total/parts as contiguous
// blocks allow (block r ends at the first row where the running sum reaches (r+1)/parts of the
// total). Blocks may be empty when there are fewer rows than parts. parts ≥ 1.
std::vector<std::uint32_t> balanced_row_blocks(std::span<const double> cost, unsigned parts);

}  // namespace ffcube
