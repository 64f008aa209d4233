// Progressive refinement. Notation: B radiosity, ΔB unshot radiosity, y = B − ΔB the radiosity
// already shot. The state always satisfies B = E + K y with K_ji = ρ_j F_ij A_i / A_j (the shooter's
// row, read as what j receives), so ΔB = E + K y − y is the residual of y, and a shot from i is a
// Southwell step on y (Gortler, Cohen, Slusallek 1993): y_i += ω ΔB_i, which leaves ΔB_i = (1 − ω) ΔB_i,
// adds K_ji ω ΔB_i to B_j and ΔB_j, and leaves B_i as it was. ω = 1 is Cohen's shooting; ω in
// (1, 2) is over-relaxation, which converges where the system is symmetrisable (reciprocal rows:
// scaled by A_j / ρ_j it is symmetric and diagonally dominant, hence positive definite, and
// coordinate descent with 0 < ω < 2 decreases its energy norm at every shot).
#include "ffcube/solver/progressive.hpp"

#include <algorithm>
#include <cmath>

#include <glm/common.hpp>

#include "ffcube/core/error.hpp"
#include "ffcube/core/timer.hpp"
#include "ffcube/solver/row_cache.hpp"
#include "internal.hpp"

namespace ffcube {
namespace {

// Rounding bound of the energy invariant. Every accumulated term (power received, absorbed,
// escaped, ΔB A summed by the scan) is rounded once with relative error ε = 1.1e-16 against a
// partial sum no larger than the turnover T (emitted + all power ever shot), so after S additions
// |emitted − absorbed − escaped − unshot| ≤ about 3 S ε T. 1e-5 × T holds for S up to 3·10^10
// non-zeros processed (days of shooting); beyond rounding, a failure is a bug in the bookkeeping.
constexpr double kEnergyTolerance = 1e-5;

// Divergence: unshot power above 1000× its best value with no improvement for a window of
// max(N, 64) shots. Without overshooting a solve that passed the stiffness rule cannot diverge
// (y = B − ΔB grows monotonically towards the solution); with overshooting on non-reciprocal rows,
// converging solves were measured rising up to about 12× before falling, while real divergence is
// geometric and passes 1000× within a few dozen shots (docs/solvers.md).
constexpr double kDivergenceGrowth = 1e3;
constexpr std::uint64_t kMinDivergenceWindow = 64;

double abs_sum(const Vec3& v) { return std::abs(v.x) + std::abs(v.y) + std::abs(v.z); }

}  // namespace

struct ProgressiveSolver::Impl {
    struct Candidate {
        double power;
        std::uint32_t patch;
    };

    const Scene& scene;
    RowProvider& provider;
    SolverOptions options;
    detail::PatchInputs in;
    std::uint64_t max_shots;
    std::uint64_t window_updates;

    // Solve state (reset() restores it).
    std::vector<Vec3> b, db;
    Vec3 absorbed{0.0}, escaped{0.0}, turnover{0.0};
    std::uint64_t shots = 0;
    StopReason status = StopReason::Running;
    DivergenceMonitor monitor;
    ConvergenceHistory history;
    double seconds = 0.0;       // time spent inside step()
    double rows_seconds = 0.0;  // of which inside the provider
    // From the last scan.
    double unshot_abs = 0.0;    // Σ_i A_i |ΔB_i| over channels
    Vec3 unshot_signed{0.0};    // Σ_i A_i ΔB_i per channel
    double energy_error = 0.0;

    // Rows (kept across reset()).
    RowCache cache;
    std::vector<bool> ever_computed;
    RowCacheStats counters;
    double max_row_sum = 0.0;

    // Per-batch scratch, reused so that shooting allocates nothing once warm.
    std::vector<Candidate> batch;
    std::vector<std::uint32_t> misses;
    std::vector<SparseRow> staged;            // rows computed for this batch, by batch slot
    std::vector<const SparseRow*> batch_rows;  // the row each batch slot shoots with

    Impl(const Scene& s, RowProvider& p, const SolverOptions& o)
        : scene(s),
          provider(p),
          options(o),
          in(detail::load_patches(s, p)),
          max_shots(effective_max_iterations(o, s.size())),
          window_updates((std::max<std::uint64_t>(s.size(), kMinDivergenceWindow) + o.batch - 1) / o.batch),
          monitor(window_updates, kDivergenceGrowth),
          history(o.history_capacity),
          cache(static_cast<std::uint32_t>(s.size()), static_cast<std::size_t>(o.row_cache_mb * 1048576.0)),
          ever_computed(s.size(), false),
          staged(o.batch),
          batch_rows(o.batch) {
        batch.reserve(o.batch);
        misses.reserve(o.batch);
        restart();
    }

    void restart() {
        b = in.emit;
        db = in.emit;
        absorbed = escaped = Vec3(0.0);
        turnover = in.emitted;
        shots = 0;
        seconds = rows_seconds = 0.0;
        monitor = DivergenceMonitor(window_updates, kDivergenceGrowth);
        history.clear();
        status = in.emitted_total > 0.0 ? StopReason::Running : StopReason::NothingToDo;
        scan();
        if (status == StopReason::Running) {
            monitor.update(fraction());
            history.offer(0.0, fraction());
            decide();
        }
    }

    double fraction() const { return in.emitted_total > 0.0 ? unshot_abs / in.emitted_total : 0.0; }

    // One pass over the patches: the unshot totals, the energy invariant, and the next batch of
    // shooters: the largest unshot powers A_i Σ_c |ΔB_ic|, ties to the lowest index (strictly
    // greater power is needed to pass a candidate already taken, and patches come in index order).
    void scan() {
        const std::uint32_t n = in.size();
        const std::size_t k_max = options.batch;
        unshot_abs = 0.0;
        unshot_signed = Vec3(0.0);
        batch.clear();
        for (std::uint32_t i = 0; i < n; ++i) {
            const double power = in.area[i] * abs_sum(db[i]);
            unshot_abs += power;
            unshot_signed += db[i] * in.area[i];
            if (!(power > 0.0) || (batch.size() == k_max && !(power > batch.back().power))) continue;
            if (batch.size() < k_max) batch.push_back({power, i});
            std::size_t pos = batch.size() - 1;
            for (; pos > 0 && batch[pos - 1].power < power; --pos) batch[pos] = batch[pos - 1];
            batch[pos] = {power, i};
        }
        if (!std::isfinite(unshot_abs)) return;  // the divergence monitor reports it
        energy_error = 0.0;
        for (int c = 0; c < 3; ++c) {
            const double defect = in.emitted[c] - absorbed[c] - escaped[c] - unshot_signed[c];
            if (turnover[c] > 0.0) energy_error = std::max(energy_error, std::abs(defect) / turnover[c]);
        }
        FFCUBE_CHECK_MSG(energy_error <= kEnergyTolerance,
                         "energy bookkeeping: emitted ≠ absorbed + escaped + unshot beyond rounding");
    }

    // Sets status from the last scan.
    void decide() {
        if (status != StopReason::Running) return;
        if (unshot_abs <= options.tolerance * in.emitted_total)
            status = StopReason::Converged;
        else if (shots >= max_shots)
            status = StopReason::IterationLimit;
    }

    // Rows for the current batch: cache hits, then one provider call for the misses in batch order.
    void fetch_rows() {
        misses.clear();
        for (std::size_t k = 0; k < batch.size(); ++k) {
            batch_rows[k] = cache.find(batch[k].patch);
            if (batch_rows[k] != nullptr)
                ++counters.rows_reused;
            else
                misses.push_back(batch[k].patch);
        }
        if (misses.empty()) return;
        const Stopwatch watch;
        std::size_t next = 0;
        provider.compute_rows(misses, [&](std::uint32_t i, const SparseRow& row) {
            FFCUBE_CHECK(next < misses.size() && i == misses[next]);
            max_row_sum = std::max(max_row_sum, detail::check_row(scene, provider, i, row, in.rho[i]));
            std::size_t slot = 0;
            while (batch[slot].patch != i) ++slot;
            staged[slot].col.assign(row.col.begin(), row.col.end());
            staged[slot].val.assign(row.val.begin(), row.val.end());
            batch_rows[slot] = &staged[slot];
            ++next;
        });
        FFCUBE_CHECK(next == misses.size());
        rows_seconds += watch.seconds();
        counters.rows_computed += misses.size();
        for (std::uint32_t i : misses) {
            if (ever_computed[i]) ++counters.rows_recomputed;
            ever_computed[i] = true;
        }
    }

    void shoot(std::uint32_t i, const SparseRow& row) {
        const Vec3 sent = options.overshoot * db[i];
        const Vec3 power = sent * in.area[i];
        db[i] -= sent;
        Vec3 absorbed_here(0.0);
        double row_sum = 0.0;
        for (std::size_t k = 0; k < row.nnz(); ++k) {
            const std::uint32_t j = row.col[k];
            const double f = row.val[k];
            row_sum += f;
            const Vec3 arriving = power * f;
            const Vec3 reflected = in.rho[j] * arriving;
            absorbed_here += arriving - reflected;
            const Vec3 dr = reflected * in.inv_area[j];
            db[j] += dr;
            b[j] += dr;
        }
        absorbed += absorbed_here;
        escaped += power * (1.0 - row_sum);
        turnover += glm::abs(power);
        ++shots;
    }

    // Keeps the rows computed for this batch, now that no cached row is in use.
    void keep_rows() {
        for (std::size_t k = 0; k < batch.size(); ++k)
            if (batch_rows[k] == &staged[k]) cache.insert(batch[k].patch, staged[k]);
    }

    void report() {
        if (!options.progress) return;
        options.progress(SolveProgress{SolverMethod::Shoot, shots, fraction(), seconds});
    }

    StopReason step(const StepBudget& budget) {
        const Stopwatch watch;
        const double start = seconds;
        std::uint64_t done = 0;
        while (status == StopReason::Running && done < budget.max_shots &&
               (done == 0 || watch.seconds() < budget.seconds)) {
            // The batch never runs past max_shots, so the iteration limit is exact; a step's own
            // shot budget is rounded up to whole batches (splitting a batch would change the order).
            if (batch.size() > max_shots - shots) batch.resize(max_shots - shots);
            fetch_rows();
            for (std::size_t k = 0; k < batch.size(); ++k) shoot(batch[k].patch, *batch_rows[k]);
            keep_rows();
            done += batch.size();
            seconds = start + watch.seconds();
            scan();
            history.offer(seconds, fraction());
            if (monitor.update(fraction())) status = StopReason::Diverged;
            decide();
            report();
        }
        seconds = start + watch.seconds();
        return status;
    }

    Vec3 ambient() const {
        if (in.total_area <= 0.0) return Vec3(0.0);
        // Cohen et al. 1988: the unshot energy, spread evenly over the area and reflected
        // 1 + ρ̄ + ρ̄² + … = 1/(1 − ρ̄) times (ρ̄ < 1 by the Kd rule).
        return (unshot_signed / in.total_area) / (Vec3(1.0) - in.mean_rho);
    }

    RowCacheStats cache_stats() const {
        RowCacheStats s = counters;
        s.rows_evicted = cache.evictions();
        s.capacity_bytes = cache.capacity_bytes();
        s.peak_bytes = cache.peak_bytes();
        s.patches_without_row =
            static_cast<std::uint64_t>(std::count(ever_computed.begin(), ever_computed.end(), false));
        return s;
    }

    EnergyBalance energy() const {
        EnergyBalance e;
        e.emitted = in.emitted;
        e.absorbed = absorbed;
        e.escaped = escaped;
        e.unshot = unshot_signed;
        e.relative_error = energy_error;
        return e;
    }
};

ProgressiveSolver::ProgressiveSolver(const Scene& scene, RowProvider& provider, const SolverOptions& options) {
    validate(options);
    impl_ = std::make_unique<Impl>(scene, provider, options);
}

ProgressiveSolver::~ProgressiveSolver() = default;

StopReason ProgressiveSolver::step(const StepBudget& budget) { return impl_->step(budget); }

StopReason ProgressiveSolver::run() { return impl_->step(StepBudget{}); }

StopReason ProgressiveSolver::status() const { return impl_->status; }
std::span<const Vec3> ProgressiveSolver::radiosity() const { return impl_->b; }
std::span<const Vec3> ProgressiveSolver::unshot_radiosity() const { return impl_->db; }
double ProgressiveSolver::unshot_fraction() const { return impl_->fraction(); }
Vec3 ProgressiveSolver::ambient() const { return impl_->ambient(); }
std::uint64_t ProgressiveSolver::shots() const { return impl_->shots; }
EnergyBalance ProgressiveSolver::energy() const { return impl_->energy(); }
RowCacheStats ProgressiveSolver::cache_stats() const { return impl_->cache_stats(); }
const SparseRow* ProgressiveSolver::cached_row(std::uint32_t i) { return impl_->cache.find(i); }
bool ProgressiveSolver::row_ever_computed(std::uint32_t i) const { return impl_->ever_computed[i]; }
double ProgressiveSolver::max_row_sum() const { return impl_->max_row_sum; }
void ProgressiveSolver::reset() { impl_->restart(); }

SolveResult ProgressiveSolver::result() const {
    const Impl& s = *impl_;
    if (s.status == StopReason::NothingToDo) return detail::nothing_to_do(s.scene, SolverMethod::Shoot);
    SolveResult r;
    r.method = SolverMethod::Shoot;
    r.radiosity = s.b;
    r.ambient = s.ambient();
    r.iterations = r.shots = s.shots;
    r.unshot_fraction = s.fraction();
    r.stop = s.status;
    r.energy = s.energy();
    r.timings.total = s.seconds;
    r.timings.rows = s.rows_seconds;
    r.timings.solve = s.seconds - s.rows_seconds;
    ConvergenceHistory h = s.history;
    h.finish(s.seconds, s.fraction());
    r.history = h.samples();
    r.cache = s.cache_stats();
    for (std::size_t i = 0; i < s.db.size(); ++i) r.unshot_abs += s.in.area[i] * glm::abs(s.db[i]);
    r.stiffness.max_row_sum = s.max_row_sum;
    if (s.status == StopReason::Diverged)
        r.warnings.push_back("progressive refinement diverged: the unshot energy grew; see docs/solvers.md");
    return r;
}

}  // namespace ffcube
