// Closed-row rebalancing and the cap at 1 (see rebalance.hpp).
#include "accuracy/rebalance.hpp"

#include <algorithm>
#include <cmath>

namespace ffcube::accuracy {

// When the inner row sums to 1 (the centre saw only front faces: no miss, no back face), so
// does the exact row of a patch in a closed scene: every point of the patch sees surfaces all
// round. Near values that are exact and far values rescaled from aliased pixels (thin slivers
// seen at grazing angles cover 0 or 3× their share of pixels) no longer add up to it (up to
// 1.6e-3 off in a 24 × 24-per-wall box). The far (non-exact) entries then share one factor that
// restores the sum; exact entries stay exact. Likewise no row may sum above 1 (energy leaving i
// cannot arrive more than once): an open row that the correction pushed above 1 gets the same
// treatment, down to 1.
Rebalance rebalance_row(std::span<double> values, std::span<const std::uint8_t> is_exact, const ClosedTest& test) {
    double fixed = 0, rest = 0;
    for (std::size_t e = 0; e < values.size(); ++e) (is_exact[e] ? fixed : rest) += values[e];
    Rebalance r;
    r.closed = test.analytic ? std::abs(fixed + rest - 1.0) <= std::max(kClosedRowTolerance, 2 * test.analytic_error)
                             : std::abs(test.inner_sum - 1.0) <= std::max(kClosedRowTolerance, test.measured_tolerance);
    if (!(r.closed || fixed + rest > 1.0)) return r;
    // Normally the non-exact entries take the whole change. Where they are too few for that
    // (the far field made nearly all of the row exact: a factor beyond 1 ± 0.1 would be pixel
    // noise amplified), every entry shares it instead: the exact ones are then moved by their
    // own quadrature error's order (about 1e-5 relative).
    const double scale = (1.0 - fixed) / rest;
    const double all = 1.0 / (fixed + rest);
    const bool rest_only = rest > 0 && std::abs(scale - 1.0) <= 0.1;
    const double factor = rest_only ? scale : all;
    if (!(std::isfinite(factor) && std::abs(factor - 1.0) <= 0.1)) return r;
    for (std::size_t e = 0; e < values.size(); ++e)
        if (!rest_only || !is_exact[e]) values[e] *= factor;
    r.applied = true;
    r.factor = factor;
    r.moved = std::abs(1.0 - factor) * (rest_only ? rest : fixed + rest);  // moved by this much
    return r;
}

}  // namespace ffcube::accuracy
