// Gathering (Jacobi, Gauss–Seidel) and the direct dense solve. Both need every row of F, fetched
// once through the provider and held in double (12 bytes per non-zero) so that all methods see
// exactly the values the provider gave. Row i is read as a gathering row: B_i = E_i + ρ_i Σ_j F_ij B_j.
#include <algorithm>
#include <array>
#include <cmath>
#include <numeric>
#include <optional>

#include <fmt/format.h>

#include <glm/common.hpp>

#include "ffcube/core/error.hpp"
#include "ffcube/core/timer.hpp"
#include "internal.hpp"

namespace ffcube::detail {
namespace {

// Rows [first, first + ptr.size() − 1) of F: all of them, or a process's block (RowBlocks).
struct RowMatrix {
    std::uint32_t first = 0;
    std::vector<std::uint64_t> ptr{0};
    std::vector<std::uint32_t> col;
    std::vector<double> val;
    std::vector<double> self;  // F_ii (0 for planar patches)
    std::vector<double> sum;   // row sums
};

// Every row, checked against the stiffness rule before any solving.
// Rows [first, last) (all of them when blocks is null).
RowMatrix fetch_all(const Scene& scene, RowProvider& provider, const PatchInputs& in, double& seconds,
                    const RowBlocks* blocks = nullptr) {
    const Stopwatch watch;
    RowMatrix f;
    f.first = blocks ? blocks->first() : 0;
    const std::uint32_t last = blocks ? blocks->last() : in.size();
    FFCUBE_CHECK(f.first <= last && last <= in.size());
    const std::uint32_t n = last - f.first;
    f.ptr.reserve(std::size_t(n) + 1);
    f.self.assign(n, 0.0);
    f.sum.resize(n);
    std::vector<std::uint32_t> all(n);
    std::iota(all.begin(), all.end(), f.first);
    provider.compute_rows(all, [&](std::uint32_t i, const SparseRow& row) {
        const std::uint32_t at = i - f.first;
        FFCUBE_CHECK(at + 1 == f.ptr.size());
        f.sum[at] = check_row(scene, provider, i, row, in.rho[i]);
        for (std::size_t k = 0; k < row.nnz(); ++k) {
            if (row.col[k] == i) f.self[at] = row.val[k];
            f.col.push_back(row.col[k]);
            f.val.push_back(row.val[k]);
        }
        f.ptr.push_back(f.col.size());
    });
    FFCUBE_CHECK(f.ptr.size() == std::size_t(n) + 1);
    seconds += watch.seconds();
    return f;
}

// One channel of (I − ρF) B = E as a SweepSystem: a_ii = 1 − ρ_i F_ii, a_ij = −ρ_i F_ij.
struct RadiosityChannel {
    const RowMatrix* f;
    std::vector<double> rho, e;

    std::uint32_t size() const { return static_cast<std::uint32_t>(rho.size()); }
    // Rows i of f's block only (f->first ≤ i < f->first + its rows).
    double diagonal(std::uint32_t i) const { return 1.0 - rho[i] * f->self[i - f->first]; }
    double rhs(std::uint32_t i) const { return e[i]; }
    double off_diagonal_dot(std::uint32_t i, std::span<const double> x) const {
        double s = 0.0;
        const std::uint32_t at = i - f->first;
        for (std::uint64_t k = f->ptr[at]; k < f->ptr[at + 1]; ++k)
            if (f->col[k] != i) s += f->val[k] * x[f->col[k]];
        return -rho[i] * s;
    }
};

std::array<RadiosityChannel, 3> channels(const RowMatrix& f, const PatchInputs& in) {
    std::array<RadiosityChannel, 3> ch;
    for (int c = 0; c < 3; ++c) {
        ch[c].f = &f;
        ch[c].rho.resize(in.size());
        ch[c].e.resize(in.size());
        for (std::uint32_t i = 0; i < in.size(); ++i) {
            ch[c].rho[i] = in.rho[i][c];
            ch[c].e[i] = in.emit[i][c];
        }
    }
    return ch;
}

// The energy balance of a gathered solution, after the fact. With H_i = Σ_j F_ij B_j (what reaches
// i, per unit area) and the residual r = E + ρH − B:
//   absorbed = Σ A_i (1 − ρ_i) H_i, escaped = Σ A_i B_i (1 − rowsum_i), unshot = Σ A_i r_i.
// emitted − absorbed − escaped − unshot = Σ_ij (A_i F_ij − A_j F_ji) B_i: zero for reciprocal rows,
// otherwise the rows' reciprocity error, so relative_error is reported but not enforced here.
// Also returns Σ_i A_i |r_i| over channels. With blocks, f holds this block's rows, and the sums
// are taken over every block.
EnergyBalance gathered_energy(const RowMatrix& f, const PatchInputs& in, std::span<const Vec3> b,
                              double& residual_abs, Vec3* residual_channels = nullptr, RowBlocks* blocks = nullptr) {
    EnergyBalance e;
    e.emitted = in.emitted;
    Vec3 turnover = blocks ? Vec3(0.0) : in.emitted, channels(0.0);
    residual_abs = 0.0;
    for (std::uint32_t at = 0; at + 1 < f.ptr.size(); ++at) {
        const std::uint32_t i = f.first + at;
        Vec3 h(0.0);
        for (std::uint64_t k = f.ptr[at]; k < f.ptr[at + 1]; ++k) h += f.val[k] * b[f.col[k]];
        const Vec3 r = in.emit[i] + in.rho[i] * h - b[i];
        const double a = in.area[i];
        e.absorbed += a * (Vec3(1.0) - in.rho[i]) * h;
        e.escaped += a * b[i] * (1.0 - f.sum[at]);
        e.unshot += a * r;
        turnover += a * glm::abs(b[i]);
        residual_abs += a * (std::abs(r.x) + std::abs(r.y) + std::abs(r.z));
        channels += a * glm::abs(r);
    }
    if (blocks) {
        std::array<double, 16> v{e.absorbed.x, e.absorbed.y, e.absorbed.z, e.escaped.x, e.escaped.y, e.escaped.z,
                                 e.unshot.x,   e.unshot.y,   e.unshot.z,   turnover.x,  turnover.y,  turnover.z,
                                 residual_abs, channels.x,   channels.y,   channels.z};
        blocks->sum(v);
        e.absorbed = Vec3(v[0], v[1], v[2]);
        e.escaped = Vec3(v[3], v[4], v[5]);
        e.unshot = Vec3(v[6], v[7], v[8]);
        turnover = Vec3(v[9], v[10], v[11]);
        residual_abs = v[12];
        channels = Vec3(v[13], v[14], v[15]);
    }
    if (blocks) turnover += in.emitted;
    if (residual_channels) *residual_channels += channels;
    for (int c = 0; c < 3; ++c)
        if (turnover[c] > 0.0)
            e.relative_error = std::max(
                e.relative_error, std::abs(e.emitted[c] - e.absorbed[c] - e.escaped[c] - e.unshot[c]) / turnover[c]);
    return e;
}

void set_stiffness_figures(SolveResult& r, const RowMatrix& f, const PatchInputs& in, RowBlocks* blocks = nullptr) {
    for (double s : f.sum) r.stiffness.max_row_sum = std::max(r.stiffness.max_row_sum, s);
    if (blocks) blocks->max(std::span<double>(&r.stiffness.max_row_sum, 1));
    for (const Vec3& rho : in.rho) r.stiffness.rho_max = std::max({r.stiffness.rho_max, rho.x, rho.y, rho.z});
}

}  // namespace

SolveResult solve_sweeps(const Scene& scene, RowProvider& provider, const SolverOptions& options) {
    const PatchInputs in = load_patches(scene, provider);
    if (!(in.emitted_total > 0.0)) return nothing_to_do(scene, options.method);
    SolveResult r;
    r.method = options.method;
    RowBlocks* blocks = options.blocks;
    const RowMatrix f = fetch_all(scene, provider, in, r.timings.rows, blocks);
    const std::array<RadiosityChannel, 3> ch = channels(f, in);
    std::array<std::vector<double>, 3> x{ch[0].e, ch[1].e, ch[2].e};  // start from B = E
    const std::array<std::span<double>, 3> xs{x[0], x[1], x[2]};

    SweepControl control;
    control.sweep = options.method == SolverMethod::Jacobi ? Sweep::Jacobi : Sweep::GaussSeidel;
    control.tolerance = options.tolerance;
    control.max_sweeps = effective_max_iterations(options, scene.size());
    ConvergenceHistory history(options.history_capacity);
    std::optional<SweepRange> range;
    if (blocks) {
        range.emplace();
        range->first = blocks->first();
        range->last = blocks->last();
        range->share = [blocks](std::span<double> v) { blocks->share(v); };
        range->total = [blocks](double v) {
            blocks->sum(std::span<double>(&v, 1));
            return v;
        };
    }
    const Stopwatch watch;
    const SweepOutcome out = sweep_until<RadiosityChannel>(
        ch, xs, in.area, in.emitted_total, control,
        [&](std::uint64_t sweeps, double fraction) {
            history.offer(watch.seconds(), fraction);
            if (options.progress && sweeps > 0)
                options.progress(SolveProgress{options.method, sweeps, fraction, watch.seconds()});
        },
        range ? &*range : nullptr);
    r.timings.solve = watch.seconds();

    r.radiosity.resize(in.size());
    for (std::uint32_t i = 0; i < in.size(); ++i) r.radiosity[i] = Vec3(x[0][i], x[1][i], x[2][i]);
    double residual_abs = 0.0;
    r.energy = gathered_energy(f, in, r.radiosity, residual_abs, &r.unshot_abs, blocks);
    set_stiffness_figures(r, f, in, blocks);
    r.iterations = out.sweeps;
    r.unshot_fraction = out.residual_fraction;
    r.stop = out.stop;
    history.finish(r.timings.solve, out.residual_fraction);
    r.history = history.samples();
    if (out.stop == StopReason::Diverged && out.stagnated)
        r.warnings.push_back(fmt::format(
            "{}: the residual did not decrease over {} sweeps: the spectral radius of the iteration is 1 or "
            "more (ρF has no steady state here); stopped as diverged",
            to_string(options.method), control.stagnation_window));
    else if (out.stop == StopReason::Diverged)
        r.warnings.push_back(fmt::format("{}: the residual grew over {} sweeps: stopped as diverged",
                                         to_string(options.method), control.divergence_window));
    return r;
}

SolveResult solve_direct(const Scene& scene, RowProvider& provider, const SolverOptions& options) {
    const PatchInputs in = load_patches(scene, provider);
    const std::uint32_t n = in.size();
    if (n > kDirectMaxPatches)
        throw InputError(fmt::format(
            "{}: --solver direct refused for {} patches (limit {}): the dense matrix I − ρF takes N² doubles "
            "({:.1f} GB here) and its LU factorisation (2/3)·N³ operations per channel; use --solver shoot "
            "(rows on demand) or gauss-seidel",
            scene.source, n, kDirectMaxPatches, double(n) * n * 8 / 1e9));
    if (!(in.emitted_total > 0.0)) return nothing_to_do(scene, SolverMethod::Direct);
    SolveResult r;
    r.method = SolverMethod::Direct;
    const RowMatrix f = fetch_all(scene, provider, in, r.timings.rows);
    const Stopwatch watch;
    r.radiosity = in.emit;
    double residual_abs = 0.0;
    gathered_energy(f, in, r.radiosity, residual_abs);
    ConvergenceHistory history(options.history_capacity);
    history.offer(0.0, residual_abs / in.emitted_total);

    DenseMatrix a(n);
    std::vector<std::uint32_t> perm;
    std::vector<double> x(n), scratch(n);
    for (int c = 0; c < 3; ++c) {
        for (std::uint32_t i = 0; i < n; ++i) {
            const std::span<double> row = a.row(i);
            std::fill(row.begin(), row.end(), 0.0);
            row[i] = 1.0;
            for (std::uint64_t k = f.ptr[i]; k < f.ptr[i + 1]; ++k) row[f.col[k]] -= in.rho[i][c] * f.val[k];
            x[i] = in.emit[i][c];
        }
        // Rows of I − ρF are strictly diagonally dominant (1 − ρ_i rowsum_i > 0 by the stiffness
        // check), so the matrix is regular and lu_factor's singular-matrix error cannot occur here.
        lu_factor(a, perm, "direct solve of I − ρF");
        lu_solve(a, perm, x, scratch);
        for (std::uint32_t i = 0; i < n; ++i) r.radiosity[i][c] = x[i];
    }
    r.timings.solve = watch.seconds();
    r.energy = gathered_energy(f, in, r.radiosity, residual_abs, &r.unshot_abs);
    set_stiffness_figures(r, f, in);
    r.iterations = 1;
    r.unshot_fraction = residual_abs / in.emitted_total;
    r.stop = StopReason::Converged;
    history.finish(r.timings.solve, r.unshot_fraction);
    r.history = history.samples();
    if (options.progress) options.progress(SolveProgress{SolverMethod::Direct, 1, r.unshot_fraction, r.timings.solve});
    return r;
}

}  // namespace ffcube::detail
