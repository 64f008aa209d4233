// Internal to the accuracy layer. One job: the per-row error estimate's terms for one entry
// (docs/accuracy.md, "Per-row error estimate"): the systematic error of the sender's midpoint
// rule, and the inner provider's noise (hemicube pixels or ray-cast samples).
#pragma once

#include <cstdint>
#include <span>

#include "ffcube/scene/scene.hpp"

namespace ffcube::accuracy {

struct RowErrorModel {
    const Scene& scene;
    const Patch& sender;        // patch i
    double pixel_delta_ff = 0;  // NearFieldOptions::pixel_delta_ff
    double rays = 0;            // NearFieldOptions::rays
    bool sampled_row = false;   // the row is the average of 2 × 2 sub-hemicubes
    bool quadrature = false;    // the sender quadrature applies to this row's provider

    // The midpoint rule's error on entry F_ij = f as the inner provider made it: relative
    // (h_i/d)²/12 (the (h/d)²/24 of docs/accuracy.md times a shape constant of at most ~2); its
    // square for a sampled row (the 2 × 2 rule's residual); 0 when the inner provider samples
    // the whole sender (the ray caster).
    double midpoint(std::uint32_t j, double f) const;
    // The same from r² = |c_j − c_i|² (the caller has it).
    double midpoint_at(double r2, double f) const;
    // The inner provider's noise on an entry of value f.
    double noise(double f) const;
    // noise(f[a]) into out[a] for every a, the same bits (two at a time where SSE2 is there).
    void noise(std::span<const double> f, double* out) const;
};

}  // namespace ffcube::accuracy
