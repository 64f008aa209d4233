// Where rows of F come from. Solvers and writers ask a RowProvider; they never see how rows are
// made (hemicubes on a GL context, ray casting, a file, a hand-made matrix in a test).
#pragma once

#include <cstdint>
#include <functional>
#include <span>
#include <string>
#include <vector>

#include "ffcube/formfactor/row_ledger.hpp"
#include "ffcube/formfactor/sparse.hpp"
#include "ffcube/geometry/polygon.hpp"

namespace ffcube {

// Receives row i. Called on the thread that called compute_rows, in the order the rows were
// listed; the row reference is valid only during the call.
using RowSink = std::function<void(std::uint32_t i, const SparseRow& row)>;

class RowProvider {
public:
    virtual ~RowProvider() = default;
    virtual std::uint32_t size() const = 0;
    virtual std::string name() const = 0;
    // Computes the listed rows (each < size()) and hands each to sink, in list order. Providers
    // may compute in parallel; results never depend on the number of threads.
    virtual void compute_rows(std::span<const std::uint32_t> rows, const RowSink& sink) = 0;
    // One row, for convenience.
    void compute_row(std::uint32_t i, SparseRow& out);

    // Planned rows. A provider that measures F from one point of the sender (the hemicube: its
    // centre) may be able to measure some rows as the weighted sum over points of the sender
    // instead, each with its own visibility ("sub-hemicubes"), and to leave out rows its caller
    // can make without it. How a row is measured is a RowRequest, worked out by the caller before
    // it asks (the plan; the provider never calls back into its caller): centre (as
    // compute_rows), sampled (sub-hemicubes at 2 × 2 sender points), sampled_fine (4 × 4, for
    // senders with an occluder touching them) or skip (nothing measured: the row handed to sink
    // is empty).
    enum class RowPlan : std::uint8_t { centre, sampled, skip, sampled_fine };
    // Which engine measures a row: the provider's own (hemicubes), or the driver's ray caster
    // (RowStages::cast), chosen per row by the driver (pipeline/row_engine.hpp).
    enum class RowEngine : std::uint8_t { provider, rays };
    // The measure step's whole input for one row: the plan, the engine, and for a sampled row the
    // sender points and their weights (Σ w = the share of the sender measured, 1 unless part of
    // it is enclosed). Empty points on a sampled row: the provider's own rule (the patch's
    // quadrature points, geometry/quadrature.hpp, 2 or 4 per axis), unless partly_enclosed says
    // the points are on the exposed part only: then none means no part is exposed, and the row
    // is empty (measured by nobody). The sender-sampling rules (which points) are the caller's
    // (accuracy: CorrectedRowProvider's plan, exposed points).
    struct RowRequest {
        RowPlan plan = RowPlan::centre;
        RowEngine engine = RowEngine::provider;
        std::vector<Vec3> points;
        std::vector<double> weights;
        bool partly_enclosed = false;  // the points cover only the exposed part of a cut sender (counted)
        bool sampled() const { return plan == RowPlan::sampled || plan == RowPlan::sampled_fine; }
        // Nothing to measure: a skipped row, or a sender with no exposed part (an empty row).
        bool empty() const { return plan == RowPlan::skip || (sampled() && partly_enclosed && points.empty()); }
        // Back to a centre row, the vectors' capacity kept (no allocation per row).
        void reset() {
            plan = RowPlan::centre;
            engine = RowEngine::provider;
            points.clear();
            weights.clear();
            partly_enclosed = false;
        }
    };
    virtual bool can_sample_sender() const { return false; }
    // Rays per row when the rows planned sampled_fine are ray-cast from the whole sender instead
    // of measured by sub-hemicubes (the driver's choice, pipeline/row_engine.hpp); 0: they are
    // not. The caller's error estimate of such a row is the rays' noise.
    virtual std::uint64_t cast_fine_row_rays() const { return 0; }
    // One request per listed row (requests.size() == rows.size()); rows go to sink in list
    // order like compute_rows. The default samples nothing and skips nothing.
    virtual void compute_rows_requested(std::span<const std::uint32_t> rows, std::span<const RowRequest> requests,
                                        const RowSink& sink);
    // The same with the plans only (the provider's own sender points; its own engine).
    void compute_rows_planned(std::span<const std::uint32_t> rows, std::span<const RowPlan> plans, const RowSink& sink);

    // Per-row work of a caller (the near-field correction, and the driver around it) that a
    // provider may run on its own worker threads, overlapped with measuring other rows, instead
    // of on the calling thread: plan(k, i, request) says how to measure row i = rows[k] (asked
    // only of providers that can_sample_sender; unset: centre; the request comes in reset, its
    // vectors' capacity kept), finish(k, i, row) works on the row as measured, in place, before
    // it goes to sink. For one k, plan and finish run on the same thread, plan first; for
    // different k they may run at the same time on different threads, so both must be
    // thread-safe, and a row must depend only on k and i, never on the schedule. Rows still go to
    // sink on the calling thread, in list order. The default runs both on the calling thread:
    // plans for a batch of rows, then compute_rows_requested (or compute_rows) for the batch.
    struct RowStages {
        std::function<void(std::size_t k, std::uint32_t i, RowRequest& request)> plan;
        std::function<void(std::size_t k, std::uint32_t i, SparseRow& row)> finish;
        // For a provider that refines each row to a tolerance (the ray caster, accuracy by
        // target). exact_entries: before row i is measured, the entries finish will replace by
        // exact values, (j, F_ij) with j increasing, valid until finish; their measuring error
        // does not count. measured: the row's estimated measuring error and the rays it took
        // (each ray's weight is 1/rays), before finish.
        std::function<std::span<const std::pair<std::uint32_t, double>>(std::size_t k, std::uint32_t i)> exact_entries;
        std::function<void(std::size_t k, std::uint32_t i, double error, double rays)> measured;
        // The driver's second engine: row i measured into `row` when its request says
        // RowEngine::rays, on the provider's worker thread `worker` (< the provider's thread
        // count; one scratch per worker), right after plan (with pipelined workers: while the
        // worker measures the row before). Thread-safe; the row depends on i only.
        std::function<void(unsigned worker, std::uint32_t i, SparseRow& row)> cast;
    };
    virtual void compute_rows_staged(std::span<const std::uint32_t> rows, const RowStages& stages,
                                     const RowSink& sink);
};

// Rows of a matrix already in memory (loaded from .ffm, or made by hand in a test).
class MatrixRowProvider final : public RowProvider {
public:
    explicit MatrixRowProvider(const CsrMatrix& m) : m_(m) {}
    std::uint32_t size() const override { return m_.size(); }
    std::string name() const override { return "matrix"; }
    void compute_rows(std::span<const std::uint32_t> rows, const RowSink& sink) override;

private:
    const CsrMatrix& m_;
};

// An inner provider's rows, passed through every entry point (compute_rows, compute_rows_requested,
// compute_rows_staged, can_sample_sender), each row shown once to observe(i, row) on its way to
// the sink: the one place where wrappers that watch (or trim) the rows forward the calls.
class ObservingRowProvider : public RowProvider {
public:
    explicit ObservingRowProvider(RowProvider& inner) : inner_(inner) {}
    std::uint32_t size() const override { return inner_.size(); }
    std::string name() const override { return inner_.name(); }
    void compute_rows(std::span<const std::uint32_t> rows, const RowSink& sink) override;
    bool can_sample_sender() const override { return inner_.can_sample_sender(); }
    std::uint64_t cast_fine_row_rays() const override { return inner_.cast_fine_row_rays(); }
    void compute_rows_requested(std::span<const std::uint32_t> rows, std::span<const RowRequest> requests,
                                const RowSink& sink) override;
    void compute_rows_staged(std::span<const std::uint32_t> rows, const RowStages& stages, const RowSink& sink) override;

protected:
    // Row i as the inner provider hands it (on the calling thread, in list order); returns the row
    // to hand on: `row` itself, or one the wrapper holds (valid until the next call).
    virtual const SparseRow& observe(std::uint32_t i, const SparseRow& row) = 0;
    RowProvider& inner() const { return inner_; }

private:
    RowSink observing(const RowSink& sink);
    RowProvider& inner_;
};

// Rows 0 .. n−1 of an inner provider that measures a larger scene, each cut to its columns below
// n: the radiating part of a scene with obstruction-only surfaces (Scene::drawn: their patches
// come last and get no row or column). What a row's cut entries sum to is kept: the share of the
// energy leaving that patch that the left-out patches intercept (not sky, not in F), goes with the
// row as its side.obstructed.
class LeadingRowProvider final : public ObservingRowProvider {
public:
    LeadingRowProvider(RowProvider& inner, std::uint32_t n);
    std::uint32_t size() const override { return n_; }
    // Not the inner provider's staged rows: its finish stage would see rows not yet cut. The
    // default (plans and finish on the calling thread, rows through compute_rows_requested) instead.
    void compute_rows_staged(std::span<const std::uint32_t> rows, const RowStages& stages, const RowSink& sink) override {
        RowProvider::compute_rows_staged(rows, stages, sink);
    }
private:
    const SparseRow& observe(std::uint32_t i, const SparseRow& full) override;
    std::uint32_t n_;
    SparseRow row_;
};

// Computes every row 0..n-1 through the provider into a CSR matrix; each row's side figures into
// *ledger when given (resized to n).
CsrMatrix compute_all_rows(RowProvider& provider, RowLedger* ledger = nullptr);

}  // namespace ffcube
