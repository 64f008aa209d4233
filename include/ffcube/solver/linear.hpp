// The iterative and direct core of the solvers, on a plain linear system A x = b. Radiosity is
// one such system per RGB channel, (I − ρF) B = E, but nothing here knows about radiosity: the
// same sweeps reproduce the textbook tables for a 2 × 2 system in the tests, and the same LU
// solves any small dense system.
#pragma once

#include <concepts>
#include <cstdint>
#include <functional>
#include <span>
#include <vector>

namespace ffcube {

// A system the sweeps can iterate on. Row i of A is split into its diagonal a_ii (never 0) and the
// rest: off_diagonal_dot(i, x) = Σ_{j≠i} a_ij x_j.
template <class S>
concept SweepSystem = requires(const S& s, std::uint32_t i, std::span<const double> x) {
    { s.size() } -> std::convertible_to<std::uint32_t>;
    { s.diagonal(i) } -> std::convertible_to<double>;
    { s.rhs(i) } -> std::convertible_to<double>;
    { s.off_diagonal_dot(i, x) } -> std::convertible_to<double>;
};

// One Jacobi sweep: next_i = (b_i − Σ_{j≠i} a_ij x_j) / a_ii, every i from the same old x.
// x and next must not overlap.
// The overloads with [first, last) update only those rows (a block of a solve split over
// processes, solver/row_blocks.hpp); x is always the whole vector.
template <SweepSystem S>
void jacobi_sweep(const S& s, std::span<const double> x, std::span<double> next, std::uint32_t first,
                  std::uint32_t last) {
    for (std::uint32_t i = first; i < last; ++i) next[i] = (s.rhs(i) - s.off_diagonal_dot(i, x)) / s.diagonal(i);
}
template <SweepSystem S>
void jacobi_sweep(const S& s, std::span<const double> x, std::span<double> next) {
    jacobi_sweep(s, x, next, 0, s.size());
}

// One Gauss–Seidel sweep in index order, in place: x_i uses the x_j (j < i) already updated.
template <SweepSystem S>
void gauss_seidel_sweep(const S& s, std::span<double> x, std::uint32_t first, std::uint32_t last) {
    for (std::uint32_t i = first; i < last; ++i) x[i] = (s.rhs(i) - s.off_diagonal_dot(i, x)) / s.diagonal(i);
}
template <SweepSystem S>
void gauss_seidel_sweep(const S& s, std::span<double> x) {
    gauss_seidel_sweep(s, x, 0, s.size());
}

// Residual of row i: r_i = b_i − (A x)_i.
template <SweepSystem S>
double residual(const S& s, std::uint32_t i, std::span<const double> x) {
    return s.rhs(i) - s.diagonal(i) * x[i] - s.off_diagonal_dot(i, x);
}

// Dense n × n matrix of doubles, row-major.
class DenseMatrix {
public:
    DenseMatrix() = default;
    explicit DenseMatrix(std::uint32_t n) : n_(n), a_(std::size_t(n) * n, 0.0) {}
    std::uint32_t size() const { return n_; }
    double& operator()(std::uint32_t i, std::uint32_t j) { return a_[std::size_t(i) * n_ + j]; }
    double operator()(std::uint32_t i, std::uint32_t j) const { return a_[std::size_t(i) * n_ + j]; }
    std::span<double> row(std::uint32_t i) { return {a_.data() + std::size_t(i) * n_, n_}; }
    std::span<const double> row(std::uint32_t i) const { return {a_.data() + std::size_t(i) * n_, n_}; }

private:
    std::uint32_t n_ = 0;
    std::vector<double> a_;
};

// A plain dense system A x = b, for the sweeps (diagonal entries must be non-zero) and the LU.
struct DenseSystem {
    DenseMatrix a;
    std::vector<double> b;

    std::uint32_t size() const { return a.size(); }
    double diagonal(std::uint32_t i) const { return a(i, i); }
    double rhs(std::uint32_t i) const { return b[i]; }
    double off_diagonal_dot(std::uint32_t i, std::span<const double> x) const {
        double s = 0.0;
        const std::span<const double> r = a.row(i);
        for (std::uint32_t j = 0; j < r.size(); ++j)
            if (j != i) s += r[j] * x[j];
        return s;
    }
};

// LU factorisation with partial pivoting, in place: afterwards `a` holds L (unit diagonal, below)
// and U (on and above the diagonal) of P·A, and perm[k] is the original row now at row k.
// Throws InputError when a pivot is exactly zero (A singular); the caller's message is better
// placed to say why, so `what` names the system in that message.
void lu_factor(DenseMatrix& a, std::vector<std::uint32_t>& perm, const char* what);
// Solves A x = b with the factors of lu_factor; b is overwritten with x. scratch: n doubles.
void lu_solve(const DenseMatrix& lu, std::span<const std::uint32_t> perm, std::span<double> b,
              std::span<double> scratch);

// y = A x for a matrix given only by its action (x and y do not overlap).
using LinearOperator = std::function<void(std::span<const double> x, std::span<double> y)>;

struct GmresControl {
    std::uint32_t restart = 30;           // Krylov vectors per cycle (memory: restart + 1 vectors of n)
    std::uint64_t max_iterations = 3000;  // products with A in all, restarts' residuals included
    // Converged when measure(r) ≤ tolerance for the true residual r = b − A x (recomputed after every
    // cycle). Within a cycle, GMRES's running estimate of ‖r‖₂ is compared with inner_tolerance.
    double tolerance = 0.0;
    double inner_tolerance = 0.0;
    // A cycle that does not bring measure(r) below stagnation × its value at the cycle's start
    // counts as stagnant; two stagnant cycles in a row stop the solve (A singular or b outside its
    // range, e.g. a spectral radius of ρF ≥ 1).
    double stagnation = 0.999;
};

struct GmresOutcome {
    bool converged = false;
    bool stagnated = false;       // stopped for lack of progress (see GmresControl::stagnation)
    std::uint64_t iterations = 0;  // products with A
    double measure = 0.0;         // measure(r) of the final true residual
};

// Restarted GMRES(m) (Saad & Schultz 1986) with modified Gram–Schmidt and Givens rotations: x holds
// the start vector and receives the result. measure(r) is the caller's stopping norm (radiosity:
// the summed unshot power, an L1 norm); the 2-norm GMRES minimises bounds it through
// inner_tolerance (‖r‖₁ ≤ √n ‖r‖₂). Never loops forever: max_iterations and the stagnation rule.
// Non-finite values stop it (not converged, stagnated).
GmresOutcome gmres(const LinearOperator& a, std::span<const double> b, std::span<double> x, const GmresControl& control,
                   const std::function<double(std::span<const double> r)>& measure);

}  // namespace ffcube
