// Internal to the GL layer. Adaptive sender sampling (issue 15): a row planned at 4 × 4
// sub-hemicubes (an occluder touching the sender) is first measured at the 2 × 2 points; this
// decides from those four samples whether the 4 × 4 ones can still change the row, and makes
// the 2 × 2 row when they cannot. Pure CPU (no GL): tested on constructed samples.
//
// The test: what a point x sees of patch j is r(x, j) = v(x, j) · U(x, j), U the unoccluded
// point-to-polygon factor (exact, geometry/analytic.hpp) and v the fraction of it that is
// visible. The kernel U varies fast beside a wall but is known exactly, so only the visibility
// is judged: the four samples give v at the 2 × 2 points, a fifth hemicube at the centre gives
// v_c there, and d(j) = U_c (v_c − v̄), v̄ the samples' weighted mean (the interpolated
// visibility at the centre), measures how far v departs from what the 2 × 2 rule integrates
// exactly. Its error is then at most about 0.6 |d| (kErrorPerDeviation: one-dimensional model
// integrands), and the row stops at 2 × 2 when that is within the tolerance, for every entry and
// for the row sum (Σ_j d(j)), beyond the pixel noise. For receivers within 2 sender sizes, where
// the 2 × 2 rule's own error on U is largest, that error (exact area-to-area factor − Σ_q w_q U_q)
// is added times v̄.
#pragma once

#include <cstdint>
#include <span>
#include <vector>

#include "ffcube/formfactor/sparse.hpp"
#include "ffcube/scene/scene.hpp"

namespace ffcube {

struct SampleAgreementOptions {
    // Per-entry and row target (absolute): the 5e-4 of the sub-hemicube-k rule
    // (docs/accuracy.md, "Which near pairs need sub-hemicubes"): issue 7's occluded-object
    // target, a fifth of issue 14's per-entry goal (2.5e-3).
    double tolerance = 5e-4;
    // ΔF of the largest pixel of the samples' hemicubes (4 / (π n²) at resolution n): the pixel
    // noise allowance, 3σ with σ = ΔF √(4√P/6) for a receiver covering P pixels (the row error
    // model's, accuracy/row_error.cpp).
    double pixel_delta_ff = 0;
};

struct SampleAgreement {
    bool refine = false;         // the 4 × 4 samples may still change the row
    double worst_entry = 0;      // largest 0.6 |d(j)| − its noise allowance (≤ tolerance: agree)
    std::uint32_t worst_col = 0;
    double worst_sum = 0;        // 0.6 |Σ_j d(j)| − its noise allowance
    std::uint32_t exact_entries = 0;  // entries given the kernel correction (within 2 sizes)
};

// Patch p's samples: rows[q] measured by the hemicube at points[q] (weights[q], Σ = 1), and
// centre by the hemicube at p's centroid, each sorted by column. When they agree, out is the
// 2 × 2 row (Σ_q w_q r_q(j), plus v̄(j) times the rule's kernel error for receivers closer than
// 2 sender sizes); otherwise out is left empty.
SampleAgreement judge_samples(const Scene& scene, std::uint32_t p, std::span<const Vec3> points,
                              std::span<const double> weights, std::span<const SparseRow> rows,
                              const SparseRow& centre, const SampleAgreementOptions& options, SparseRow& out);

}  // namespace ffcube
