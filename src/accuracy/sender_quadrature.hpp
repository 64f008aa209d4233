// Internal to the accuracy layer. One job: the sender quadrature (docs/accuracy.md, 2.): the
// ratio Q_ij / M_ij by which an entry the inner provider measured from i's centre is rescaled
// to the 2 × 2 rule over patch i, with the guards that leave an entry alone, and the
// systematic error that remains.
#pragma once

#include <cstdint>
#include <span>
#include <vector>

#include "accuracy/patch_set.hpp"
#include "accuracy/row_error.hpp"
#include "ffcube/accuracy/near_field.hpp"

namespace ffcube::accuracy {

// Whether some column of a row of patch i lies within quadrature_k sizes of it (beyond, the
// midpoint rule's relative error (h/d)²/24 is below 1e-5 and the entry is left as it is).
// O(nnz) flops.
bool sender_quadrature_needed(const PatchSet& patches, const NearFieldOptions& options, std::uint32_t i,
                              std::span<const std::uint32_t> columns);

// The rescaling of one row's entries. `needed`: sender_quadrature_needed for the row (when
// false, entries keep their value and only their midpoint error is estimated). The rule's
// points and weights on patch i are made into the given vectors (reused across rows).
class SenderQuadrature {
public:
    SenderQuadrature(const PatchSet& patches, const NearFieldOptions& options, std::uint32_t i,
                     const RowErrorModel& error, bool needed, std::vector<Vec3>& points, std::vector<double>& weights);

    struct Entry {
        double value = 0;       // the entry after rescaling (or as it was)
        double systematic = 0;  // its remaining systematic error (the row estimate's term)
        bool rescaled = false;  // the ratio was applied (NearFieldStats::quadrature)
    };
    Entry rescale(std::uint32_t j, double f) const;

private:
    static constexpr std::size_t kMaxKernelPoints = 6;  // the centroid, the 2 × 2 rule's 3 or 4 points, padding

    Entry ratio(double f, double r) const;
    void point_kernels(const Vec3& c, const Vec3& nj, double* out) const;
    double point_kernel_scalar(const Vec3& c, const Vec3& nj, const Vec3& x) const;

    const PatchSet& patches_;
    const NearFieldOptions& options_;
    const Patch& pi_;
    const RowErrorModel& error_;
    bool needed_;
    std::span<const Vec3> qp_;
    std::span<const double> qw_;
    // The point kernel's points as columns (point_kernels): [0] the centroid, [1, npts_) the
    // rule's, the rest padding (needed_ rows only).
    std::size_t npts_ = 0;
    alignas(16) double px_[kMaxKernelPoints] = {}, py_[kMaxKernelPoints] = {}, pz_[kMaxKernelPoints] = {};
};

}  // namespace ffcube::accuracy
