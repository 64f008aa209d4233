// The default solve: progressive refinement that watches its own decay and, on stiff scenes,
// finishes with GMRES on the rows it already holds (docs/solvers.md, "Stiff scenes").
//
// Why: a shot removes the shooter's unshot power and hands on at most q = ρ_max × rowsum of it, so
// in a closed scene with ρ near 1 the unshot power falls by about ρ per "generation" (every patch
// shooting once): reaching a fraction τ takes ln τ / ln ρ generations, 9 200 × N shots at ρ = 0.999
// and τ = 1e-4. Krylov methods see the slow mode (the uniform one, eigenvalue 1 − ρ of I − ρF) as
// one direction and converge in a few dozen products with the rows, whatever ρ is.
//
// The finish solves the shooting form of the equations, so that its answer is the one shooting
// would have converged to (the shooter's row read as what j receives; docs/solvers.md): in power
// variables u_i = A_i y_i (y = B − ΔB, the radiosity already shot), per channel,
//     (I − K') u = A∘E,   (K'u)_j = ρ_j Σ_i F_ij u_i,
// with B_j = E_j + (K'u)_j / A_j, and the residual (A∘E − (I − K')u)_j = A_j ΔB_j is the unshot power:
// the stopping rule and the error bound mean the same as for shooting. Products with K' need the
// rows of the patches where u is non-zero only: the rows of the patches that have shot (all in
// the row cache unless it evicted them) and of any patch the Krylov vectors reach.
#include <algorithm>
#include <array>
#include <cmath>

#include <fmt/format.h>

#include "ffcube/core/error.hpp"
#include "ffcube/core/timer.hpp"
#include "ffcube/solver/linear.hpp"
#include "ffcube/solver/progressive.hpp"
#include "internal.hpp"

namespace ffcube::detail {
namespace {

// Rows held for the finish, fetched on demand: from the solver's row cache when it has them,
// otherwise from the provider (checked against the stiffness rule like every row).
class FinishRows {
public:
    FinishRows(const Scene& scene, RowProvider& provider, ProgressiveSolver& solver, const PatchInputs& in)
        : scene_(scene), provider_(provider), solver_(solver), in_(in), rows_(in.size()), sum_(in.size(), 0.0),
          have_(in.size(), false) {}

    // Makes sure the rows of every i with x_k[i] ≠ 0 in any of the given vectors are held.
    void ensure(std::span<const double> x) {
        missing_.clear();
        for (std::uint32_t i = 0; i < x.size(); ++i) {
            if (x[i] == 0.0 || have_[i]) continue;
            if (const SparseRow* row = solver_.cached_row(i)) {
                rows_[i] = *row;
                sum_[i] = row->sum();
                have_[i] = true;
            } else {
                missing_.push_back(i);
            }
        }
        if (missing_.empty()) return;
        const Stopwatch watch;
        std::size_t next = 0;
        provider_.compute_rows(missing_, [&](std::uint32_t i, const SparseRow& row) {
            FFCUBE_CHECK(next < missing_.size() && i == missing_[next]);
            sum_[i] = check_row(scene_, provider_, i, row, in_.rho[i]);
            rows_[i].col.assign(row.col.begin(), row.col.end());
            rows_[i].val.assign(row.val.begin(), row.val.end());
            have_[i] = true;
            ++next;
        });
        FFCUBE_CHECK(next == missing_.size());
        rows_seconds += watch.seconds();
        computed += missing_.size();
        for (std::uint32_t i : missing_)
            if (solver_.row_ever_computed(i)) ++recomputed;
    }

    const SparseRow& row(std::uint32_t i) const { return rows_[i]; }
    double sum(std::uint32_t i) const { return sum_[i]; }
    bool has(std::uint32_t i) const { return have_[i]; }

    double rows_seconds = 0.0;
    std::uint64_t computed = 0;    // rows asked from the provider
    std::uint64_t recomputed = 0;  // of which the solver had computed before (evicted since)

private:
    const Scene& scene_;
    RowProvider& provider_;
    ProgressiveSolver& solver_;
    const PatchInputs& in_;
    std::vector<SparseRow> rows_;
    std::vector<double> sum_;
    std::vector<bool> have_;
    std::vector<std::uint32_t> missing_;
};

// Shots of plain shooting worth one GMRES finish, per patch: the finish costs a few dozen
// products with all rows per channel (each about N shots' worth of row traversal) plus the rows
// not yet computed. Plain shooting goes on while it predicts fewer further shots than this × N.
constexpr double kFinishShotsPerPatch = 300.0;

// Products with K' allowed to the finish, per channel.
constexpr std::uint64_t kFinishMaxProducts = 5000;

double rho_max(const PatchInputs& in, int c) {
    double m = 0.0;
    for (const Vec3& r : in.rho) m = std::max(m, r[c]);
    return m;
}

void finish_with_gmres(const Scene& scene, RowProvider& provider, ProgressiveSolver& solver, const PatchInputs& in,
                       const SolverOptions& options, SolveResult& r) {
    const Stopwatch watch;
    const std::uint32_t n = in.size();
    FinishRows rows(scene, provider, solver, in);
    const std::span<const Vec3> b_now = solver.radiosity(), db_now = solver.unshot_radiosity();

    std::vector<Vec3> b_out(n), db_out(n);
    std::vector<double> u(n), rhs(n), scratch(n);
    bool any_stagnated = false;
    std::uint64_t products = 0;
    Vec3 absorbed(0.0), escaped(0.0), unshot(0.0), turnover = in.emitted;
    for (int c = 0; c < 3; ++c) {
        for (std::uint32_t i = 0; i < n; ++i) {
            u[i] = in.area[i] * (b_now[i][c] - db_now[i][c]);
            rhs[i] = in.area[i] * in.emit[i][c];
        }
        // y = (I − K') x, scattering row i's share of x_i: rows only where x is non-zero.
        const LinearOperator apply = [&](std::span<const double> x, std::span<double> y) {
            rows.ensure(x);
            std::copy(x.begin(), x.end(), y.begin());
            for (std::uint32_t i = 0; i < n; ++i) {
                if (x[i] == 0.0) continue;
                const SparseRow& row = rows.row(i);
                for (std::size_t k = 0; k < row.nnz(); ++k) y[row.col[k]] -= in.rho[row.col[k]][c] * row.val[k] * x[i];
            }
        };
        const auto measure = [](std::span<const double> res) {
            double s = 0.0;
            for (double v : res) s += std::abs(v);
            return s;
        };
        // The tolerance Σ_c Σ_i A_i |ΔB_ic| ≤ τ × emitted shared among the channels by their
        // emitted power (0.9 of it, so that the sum over channels stays below τ after rounding).
        GmresControl control;
        control.tolerance = 0.9 * options.tolerance * in.emitted[c];
        control.inner_tolerance = control.tolerance / std::sqrt(double(std::max<std::uint32_t>(n, 1)));
        control.max_iterations = kFinishMaxProducts;
        const GmresOutcome out = gmres(apply, rhs, u, control, measure);
        products += out.iterations;
        any_stagnated = any_stagnated || out.stagnated;

        // B = E + K'u / A, ΔB = residual / A, and the energy balance of the final state.
        apply(u, scratch);  // (I − K') u
        for (std::uint32_t i = 0; i < n; ++i) {
            const double received = u[i] - scratch[i];  // (K'u)_i
            b_out[i][c] = in.emit[i][c] + received * in.inv_area[i];
            const double res = rhs[i] - scratch[i];
            db_out[i][c] = res * in.inv_area[i];
            unshot[c] += res;
            // (1 − ρ_j) of what arrived is absorbed; received = ρ_j × arrived.
            if (in.rho[i][c] > 0.0) absorbed[c] += received * (1.0 - in.rho[i][c]) / in.rho[i][c];
            if (u[i] != 0.0) {
                escaped[c] += u[i] * (1.0 - rows.sum(i));
                turnover[c] += std::abs(u[i]);
            }
        }
        // Patches with ρ_j = 0 in this channel absorb all that arrives: count it from the rows.
        for (std::uint32_t i = 0; i < n; ++i) {
            if (u[i] == 0.0) continue;
            const SparseRow& row = rows.row(i);
            for (std::size_t k = 0; k < row.nnz(); ++k)
                if (in.rho[row.col[k]][c] == 0.0) absorbed[c] += row.val[k] * u[i];
        }
    }

    double unshot_abs = 0.0;
    Vec3 per_channel(0.0);
    for (std::uint32_t i = 0; i < n; ++i)
        for (int c = 0; c < 3; ++c) per_channel[c] += in.area[i] * std::abs(db_out[i][c]);
    unshot_abs = per_channel.x + per_channel.y + per_channel.z;
    const double fraction = unshot_abs / in.emitted_total;

    // Keep the finish only when it improved on shooting (it always should; a stagnated GMRES on a
    // pathological system must not make the answer worse).
    if (!(fraction <= r.unshot_fraction)) {
        r.warnings.push_back(fmt::format(
            "stiff scene: the GMRES finish did not improve on shooting (unshot {:.3e} against {:.3e}); kept the "
            "shooting result",
            fraction, r.unshot_fraction));
        r.stiffness.action = "gmres (rejected)";
        r.stop = StopReason::IterationLimit;
    } else {
        r.radiosity = std::move(b_out);
        r.unshot_fraction = fraction;
        r.unshot_abs = per_channel;
        r.stop = fraction <= options.tolerance ? StopReason::Converged : StopReason::IterationLimit;
        r.energy.unshot = unshot;
        r.energy.absorbed = absorbed;
        r.energy.escaped = escaped;
        r.energy.relative_error = 0.0;
        for (int c = 0; c < 3; ++c)
            if (turnover[c] > 0.0)
                r.energy.relative_error =
                    std::max(r.energy.relative_error,
                             std::abs(in.emitted[c] - absorbed[c] - escaped[c] - unshot[c]) / turnover[c]);
        if (in.total_area > 0.0) r.ambient = (unshot / in.total_area) / (Vec3(1.0) - in.mean_rho);
    }
    if (r.stop != StopReason::Converged)
        r.warnings.push_back(fmt::format("stiff scene: the GMRES finish stopped {} after {} products with the rows, "
                                         "unshot fraction {:.3e} > tolerance {:.1e}",
                                         any_stagnated ? "for lack of progress" : "at its limit", products,
                                         r.unshot_fraction, options.tolerance));
    r.stiffness.krylov_products = products;
    r.stiffness.finish_rows_computed = rows.computed;
    r.cache.rows_computed += rows.computed;
    r.cache.rows_recomputed += rows.recomputed;
    std::uint64_t without = 0;
    for (std::uint32_t i = 0; i < n; ++i)
        if (!solver.row_ever_computed(i) && !rows.has(i)) ++without;
    r.cache.patches_without_row = without;
    for (std::uint32_t i = 0; i < n; ++i)
        if (rows.has(i)) r.stiffness.max_row_sum = std::max(r.stiffness.max_row_sum, rows.sum(i));
    const double seconds = watch.seconds();
    r.timings.total += seconds;
    r.timings.rows += rows.rows_seconds;
    r.timings.solve += seconds - rows.rows_seconds;
    if (r.history.size() >= options.history_capacity) r.history.pop_back();
    r.history.push_back({r.timings.total, r.unshot_fraction});
    if (options.progress) options.progress(SolveProgress{SolverMethod::Shoot, r.shots, r.unshot_fraction, r.timings.total});
}

}  // namespace

SolveResult solve_shooting(const Scene& scene, RowProvider& provider, const SolverOptions& options) {
    ProgressiveSolver solver(scene, provider, options);
    const PatchInputs in = load_patches(scene, provider);
    const std::uint32_t n = in.size();
    StiffnessReport st;
    for (int c = 0; c < 3; ++c) st.rho_max = std::max(st.rho_max, rho_max(in, c));
    // A priori: in a closed scene each generation (every patch shooting once) keeps about ρ of the
    // unshot power, so plain shooting needs about ln τ / ln ρ_max generations.
    if (st.rho_max > 0.0 && st.rho_max < 1.0 && options.tolerance > 0.0 && options.tolerance < 1.0)
        st.predicted_generations = std::log(options.tolerance) / std::log(st.rho_max);

    const std::uint64_t limit = effective_max_iterations(options, n);
    const std::uint64_t window = std::max<std::uint64_t>(n, 64);
    const bool may_switch = options.stiff_switch && options.tolerance > 0.0;
    bool switched = false;
    while (solver.status() == StopReason::Running) {
        const double f0 = solver.unshot_fraction();
        const std::uint64_t s0 = solver.shots();
        if (solver.step(StepBudget{.max_shots = window}) != StopReason::Running) break;
        const double f1 = solver.unshot_fraction();
        const std::uint64_t s1 = solver.shots();
        if (!(f1 < f0) || !(f1 > 0.0) || s1 == s0) continue;  // no decay measured (overshooting transient)
        // Geometric decay measured over the last window, extrapolated to the tolerance.
        const double per_shot = std::log(f0 / f1) / double(s1 - s0);
        const double remaining = std::log(f1 / options.tolerance) / per_shot;
        st.decay_per_window = f1 / f0;
        st.window_shots = s1 - s0;
        st.predicted_shots = double(s1) + remaining;
        if (!may_switch) continue;
        const bool slow = remaining > kFinishShotsPerPatch * double(n);
        const bool over = double(s1) + remaining > double(limit);
        if (!slow && !over) continue;
        st.stiff = true;
        st.switched_at_shot = s1;
        st.reason = fmt::format(
            "the unshot power fell by a factor {:.6f} over the last {} shots (ρ_max = {:.6g}): plain shooting "
            "would need about {:.3g} more shots{}, {}",
            f1 / f0, s1 - s0, st.rho_max, remaining, over ? fmt::format(" (limit {})", limit) : std::string(),
            over ? "beyond the shot limit" : fmt::format("more than {:.0f} × N; GMRES on the rows is cheaper", kFinishShotsPerPatch));
        switched = true;
        break;
    }
    SolveResult r = solver.result();
    st.max_row_sum = solver.max_row_sum();
    r.stiffness = st;
    if (switched) {
        r.stiffness.action = "gmres";
        finish_with_gmres(scene, provider, solver, in, options, r);
    } else if (r.stop == StopReason::IterationLimit && st.predicted_shots > 0.0) {
        r.stiffness.stiff = true;
        r.stiffness.reason = fmt::format("plain shooting reached the shot limit; it predicted {:.3g} shots in all",
                                         st.predicted_shots);
    }
    return r;
}

}  // namespace ffcube::detail
