#include "ffcube/pipeline/row_source.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <mutex>
#include <span>

#include "ffcube/accuracy/enforce.hpp"
#include "ffcube/core/error.hpp"
#include "ffcube/core/log.hpp"
#include "ffcube/core/progress.hpp"
#include "ffcube/core/stats.hpp"
#include "ffcube/core/timer.hpp"
#include "ffcube/geometry/analytic.hpp"

namespace ffcube {

RowSource::~RowSource() = default;

namespace {
// The outermost provider of a RowSource: each row's side figures noted in the source's ledger.
class NotingRowProvider final : public ObservingRowProvider {
public:
    NotingRowProvider(RowProvider& inner, RowLedger& ledger) : ObservingRowProvider(inner), ledger_(ledger) {}

private:
    const SparseRow& observe(std::uint32_t i, const SparseRow& row) override {
        ledger_.note(i, row.side);
        return row;
    }
    RowLedger& ledger_;
};
}  // namespace

const RowLedger& RowSource::ledger() const {
    static const RowLedger none;
    return ledger_ ? *ledger_ : none;
}
RowLedger& RowSource::ledger() {
    FFCUBE_CHECK_MSG(ledger_ != nullptr, "RowSource::ledger() on a source that was never made");
    return *ledger_;
}

RowProvider& RowSource::provider() {
    // wrap() makes it on every source made, around the outermost of the others.
    FFCUBE_CHECK_MSG(noting_ != nullptr, "RowSource::provider() on a source that was never made");
    return *noting_;
}

RowSource make_row_source(const Scene& radiating, const RowOptions& options) {
    validate(options);
    const Scene& scene = radiating.drawn_scene();
    RowSource rows;
    rows.options_ = resolve_row_method(options, scene);
    Stopwatch watch;
    if (rows.options_.method == RowMethod::Raycast)
        rows.raycast_ = std::make_unique<RaycastRowProvider>(scene, raycast_options(rows.options_));
    else
        rows.hemicube_ = std::make_unique<HemicubeRowProvider>(scene, hemicube_options(rows.options_));
    rows.wrap(radiating);
    rows.setup_seconds_ = watch.seconds();
    return rows;
}

namespace {

// The ray caster refined to the tolerance, one thread (each call is one row, from a hemicube
// worker's thread), made on its first row: Embree starts threads, and the hemicube's worker
// processes are forked while this process has one. Concurrent calls are safe: the ray caster's
// rows are (RaycastRowProvider::cast_row), and a single-row call runs on the caller's thread.
class LazyRayRefiner final : public RowProvider {
public:
    LazyRayRefiner(const Scene& scene, const RowOptions& o) : scene_(scene), options_(raycast_options(o)) {
        options_.threads = 1;
        options_.tolerance = o.tolerance;
    }
    std::uint32_t size() const override { return static_cast<std::uint32_t>(scene_.size()); }
    std::string name() const override { return "raycast"; }
    void compute_rows(std::span<const std::uint32_t> rows, const RowSink& sink) override {
        compute_rows_staged(rows, RowStages{}, sink);
    }
    void compute_rows_staged(std::span<const std::uint32_t> rows, const RowStages& stages, const RowSink& sink) override {
        RaycastRowProvider* caster = nullptr;
        {
            const std::lock_guard lock(mutex_);
            if (!caster_) caster_ = std::make_unique<RaycastRowProvider>(scene_, options_);
            caster = caster_.get();
        }
        caster->compute_rows_staged(rows, stages, sink);
    }

private:
    const Scene& scene_;
    RaycastOptions options_;
    std::mutex mutex_;
    std::unique_ptr<RaycastRowProvider> caster_;
};

// The hemicube drawn again at a finer resolution, one thread with its own context (each call is
// one row, from a worker's pool thread of the hemicube provider), made on its first row, after the
// workers fork. Calls are serialized: a context belongs to one thread at a time, and rows above
// the target are few. The row is drawn with the plan its first measure had, by sub-hemicubes
// (never rays: a ray-cast row is not drawn again).
class LazyHemicubeRefiner final : public RowProvider {
public:
    LazyHemicubeRefiner(const Scene& scene, const RowOptions& o, int resolution) : scene_(scene), options_(hemicube_options(o)) {
        options_.resolution = resolution;
        options_.threads = 1;
        options_.worker_processes = false;
    }
    std::uint32_t size() const override { return static_cast<std::uint32_t>(scene_.size()); }
    std::string name() const override { return "hemicube"; }
    bool can_sample_sender() const override { return true; }
    void compute_rows(std::span<const std::uint32_t> rows, const RowSink& sink) override {
        const std::lock_guard lock(mutex_);
        provider().compute_rows(rows, sink);
    }
    void compute_rows_requested(std::span<const std::uint32_t> rows, std::span<const RowRequest> requests,
                                const RowSink& sink) override {
        const std::lock_guard lock(mutex_);
        provider().compute_rows_requested(rows, requests, sink);
    }

private:
    HemicubeRowProvider& provider() {
        if (!drawer_) drawer_ = std::make_unique<HemicubeRowProvider>(scene_, options_);
        return *drawer_;
    }
    const Scene& scene_;
    HemicubeOptions options_;
    std::mutex mutex_;
    std::unique_ptr<HemicubeRowProvider> drawer_;
};

}  // namespace

bool refine_hemicube_rows(const RowOptions& o) {
    return o.method == RowMethod::Hemicube && o.correct == Correction::Near && o.tolerance > 0 && o.tolerance_given &&
           !o.rays_given;
}

void RowSource::wrap(const Scene& radiating) {
    const Scene& scene = radiating.drawn_scene();
    // The hemicube's rows go through the driver, which gives the rows planned for the ray caster
    // to it (engine_for_row; it refuses a --fine-rows choice the scene rules out).
    if (hemicube_)
        driver_ = std::make_unique<RowDriver>(scene, *hemicube_, options_.fine_rows, options_.fine_row_rays, options_.seed,
                                             options_.cost_model);
    if (options_.correct == Correction::Near) {
        RowProvider& inner = driver_ ? static_cast<RowProvider&>(*driver_) : *raycast_;
        corrected_ = std::make_unique<CorrectedRowProvider>(scene, inner, near_field_options(options_));
        if (hemicube_ && refine_hemicube_rows(options_)) {
            // Drawn again at 2N and 4N (at most kMaxRefinedResolution), then by rays.
            std::vector<CorrectedRowProvider::Refiner> refiners;
            int last = options_.resolution;
            for (const int factor : {2, 4}) {
                const int n = std::min(factor * options_.resolution, kMaxRefinedResolution);
                if (n <= last) continue;
                last = n;
                redrawers_.push_back(std::make_unique<LazyHemicubeRefiner>(scene, options_, n));
                refiners.push_back({redrawers_.back().get(), near_field_options_for_hemicube(n).pixel_delta_ff});
            }
            refiner_ = std::make_unique<LazyRayRefiner>(scene, options_);
            refiners.push_back({refiner_.get(), 0.0});
            corrected_->refine_with(std::move(refiners), options_.tolerance);
        }
    }
    if (radiating.drawn) {
        RowProvider& inner = corrected_ ? static_cast<RowProvider&>(*corrected_)
                             : driver_   ? static_cast<RowProvider&>(*driver_)
                                         : *raycast_;
        leading_ = std::make_unique<LeadingRowProvider>(inner, static_cast<std::uint32_t>(radiating.size()));
    }
    RowProvider& outer = leading_     ? static_cast<RowProvider&>(*leading_)
                         : corrected_ ? static_cast<RowProvider&>(*corrected_)
                         : driver_    ? static_cast<RowProvider&>(*driver_)
                                      : *raycast_;
    ledger_ = std::make_unique<RowLedger>(static_cast<std::uint32_t>(radiating.size()));
    noting_ = std::make_unique<NotingRowProvider>(outer, *ledger_);
}

void rebind_row_source(RowSource& rows, const Scene& radiating) {
    if (!rows.hemicube_) {  // nothing to keep: the ray caster starts no workers
        const RowOptions options = rows.options_;
        rows = RowSource{};
        rows = make_row_source(radiating, options);
        return;
    }
    Stopwatch watch;
    rows.noting_.reset();  // the wrappers refer to the provider and the old scene: they go first
    rows.leading_.reset();
    rows.corrected_.reset();
    rows.refiner_.reset();
    rows.redrawers_.clear();
    rows.driver_.reset();
    rows.hemicube_->set_scene(radiating.drawn_scene());
    rows.wrap(radiating);
    rows.setup_seconds_ = watch.seconds();
}

std::vector<std::string> describe(const RowSource& rows) {
    std::vector<std::string> lines;
    if (const RaycastRowProvider* r = rows.raycast())
        lines.push_back(fmt::format("raycast (Embree), {} thread(s), {}{}", r->threads(),
                                    r->tolerance() > 0
                                        ? fmt::format("{} to {}", tolerance_rays(r->tolerance()).least,
                                                      tolerance_rays(r->tolerance()).most) +
                                              fmt::format(" rays per patch until each row is within --tolerance {:g}",
                                                          r->tolerance())
                                        : fmt::format("{} rays per patch", r->rays()),
                                    rows.options().auto_raycast
                                        ? fmt::format(" (--method {}; --method hemicube draws hemicubes)",
                                                      rows.options().method_choice)
                                        : ""));
    if (const HemicubeRowProvider* h = rows.hemicube())
        lines.push_back(fmt::format("hemicube on {} ({}), {} {}, resolution {}", h->backend(), h->renderer(), h->threads(),
                                    h->workers(), h->resolution()));
    if (const CorrectedRowProvider* c = rows.corrected()) {
        const NearFieldOptions nf = near_field_options(rows.options());
        lines.push_back(fmt::format(
            "near-field correction: k = {}{}{}, far field {}", nf.k, nf.sender_quadrature ? ", sender quadrature" : "",
            nf.min_near_value > 0
                ? fmt::format(", near pairs provably below F = {} keep their ray estimate (--near-min-ff)", nf.min_near_value)
                : "",
            c->corrector().far_field_status()));
        if (const CostModel& m = rows.options().cost_model; !m.builtin() && rows.hemicube())
            lines.push_back(fmt::format("cost model from {}: {} ns per hemicube pixel, CPU x {}, {} ns a piece, {} ns a ray "
                                        "(built-in: 5 ns, x 1, 500 ns, 60 ns)",
                                        m.source, m.pixel_ns, m.cpu_scale, m.piece_ns, m.ray_ns));
        if (const RowDriver* d = rows.driver(); d && d->fine_rows_by_rays())
            lines.push_back(fmt::format("rows an occluder touches (planned at 4 x 4 sub-hemicubes) ray-cast, {} rays "
                                        "each{}", d->fine_row_rays(),
                                        rows.options().fine_rows == FineRows::automatic
                                            ? " (--fine-rows auto: a scene of 1000 pieces or more; --fine-rows "
                                              "hemicubes draws them)"
                                            : ""));
    }
    return lines;
}

FfmMetadata row_metadata(const RowOptions& o) {
    FfmMetadata meta;
    meta.method = std::string(to_string(o.method));
    if (o.method == RowMethod::Raycast) {
        // sampler: the rays of an older build (padded strata) are other rows: not resumed into.
        meta.settings = rays_refined(o) ? fmt::format("tolerance={} seed={} sampler=sobol-replicates", o.tolerance, o.seed)
                                        : fmt::format("rays={} seed={} sampler=sobol", o.rays, o.seed);
    } else {
        meta.resolution = static_cast<std::uint32_t>(o.resolution);
        meta.settings = fmt::format("rotate={} seed={}", o.rotate ? 1 : 0, o.seed);
        // Recorded whether or not the rows above it are measured again (the report says which
        // rows meet it); refined rows differ from the drawn ones.
        if (o.tolerance > 0) meta.settings += fmt::format(" tolerance={}", o.tolerance);
        if (refine_hemicube_rows(o)) meta.settings += " refine=redraw,rays";
    }
    // Corrected rows differ from plain ones: checkpoints and matrices must not mix them.
    if (o.correct == Correction::Near) {
        meta.settings += fmt::format(" correct=near k={}", o.near_k);
        if (o.method == RowMethod::Raycast) meta.settings += fmt::format(" near_min_ff={}", o.near_min_ff);
        if (o.far_field != FarFieldMode::automatic) meta.settings += fmt::format(" far_field={}", to_string(o.far_field));
        if (o.method == RowMethod::Hemicube && o.sub_hemicube_k != 10.0)
            meta.settings += fmt::format(" sub_hemicube_k={}", o.sub_hemicube_k);
        // auto is the hemicube's default (and off the ray caster's): written only when not.
        if (!o.exact_visibility_auto && o.exact_visibility_occluders > 0)
            meta.settings += fmt::format(" exact_visibility={}", o.exact_visibility_occluders);
        else if (!o.exact_visibility_auto && o.method == RowMethod::Hemicube)
            meta.settings += " exact_visibility=off";
        // The emitting rows' far field (solve's default): their rows differ where it applies.
        if (o.method == RowMethod::Hemicube && o.far_field_emitters && o.far_field == FarFieldMode::automatic)
            meta.settings += " far_field_emitters=1";
        // Rows planned at 4 × 4 by rays or by hemicubes: auto (the default) resolves by the scene,
        // which the checkpoint's fingerprint holds; an explicit choice or ray count is written.
        if (o.method == RowMethod::Hemicube && o.fine_rows != FineRows::automatic)
            meta.settings += o.fine_rows == FineRows::rays ? " fine_rows=rays" : " fine_rows=hemicubes";
        if (o.method == RowMethod::Hemicube && o.fine_row_rays != 0 && o.fine_rows != FineRows::hemicubes)
            meta.settings += fmt::format(" fine_row_rays={}", o.fine_row_rays);
        // A cost model moves the automatic choices (far field, exact visibility): recorded when
        // it is not the built-in one.
        // With the method by costs (auto), piece_ns and ray_ns too: the 4 × 4 rows' engine.
        if (o.method == RowMethod::Hemicube && !o.cost_model.builtin())
            meta.settings += fmt::format(" cost_model={}/{}/{}/{}", o.cost_model.pixel_ns, o.cost_model.cpu_scale,
                                         o.cost_model.piece_ns, o.cost_model.ray_ns);
    }
    return meta;
}

namespace {

// `rows`: how many rows the caller asks for (the radiating ones; the estimates cover the scene as
// drawn).
// Accuracy by target: the target, what the rows' estimates came to (median, 95th percentile,
// largest), and the rows above it, counted and the first ones named (also on stderr: never
// accepted silently).
void report_tolerance(Report& r, const CorrectedRowProvider& corrected, const RowOptions& o, std::span<const float> est) {
    if (!(o.tolerance > 0)) return;
    std::vector<double> v;
    std::vector<std::uint32_t> above;
    for (std::size_t i = 0; i < est.size(); ++i) {
        if (std::isnan(est[i])) continue;
        v.push_back(est[i]);
        if (!(est[i] <= o.tolerance)) above.push_back(static_cast<std::uint32_t>(i));
    }
    const bool refined = o.method == RowMethod::Raycast ? rays_refined(o) : refine_hemicube_rows(o);
    const char* why = refined ? ""
                      : o.rays_given ? "--rays fixes the ray count"
                      : o.method == RowMethod::Hemicube && o.correct == Correction::Near
                          ? "hemicube rows are measured again only for a target asked for (--tolerance, a .vs3's eps)"
                          : "--correct none";
    r.set("tolerance.target", o.tolerance);
    r.set("tolerance.rows_refined", refined);
    if (o.method == RowMethod::Hemicube) {
        r.set("tolerance.rows_drawn_again", corrected.rows_redrawn());
        r.set("tolerance.rows_measured_again_by_rays", corrected.rows_refined());
    }
    r.set("tolerance.not_refined_because", why);
    r.set("tolerance.rows", v.size());
    r.set("tolerance.rows_above", above.size());
    const auto at = [&](double q) {
        if (v.empty()) return 0.0;
        std::vector<double> s = v;
        const std::size_t k = std::min(s.size() - 1, static_cast<std::size_t>(std::ceil(q * static_cast<double>(s.size())) - 1));
        std::nth_element(s.begin(), s.begin() + static_cast<std::ptrdiff_t>(k), s.end());
        return s[k];
    };
    r.set("tolerance.estimate_median", at(0.5));
    r.set("tolerance.estimate_p95", at(0.95));
    r.set("tolerance.estimate_max", v.empty() ? 0.0 : *std::max_element(v.begin(), v.end()));
    std::vector<std::string> named;
    for (std::size_t k = 0; k < above.size() && k < 20; ++k) named.push_back(corrected.patch_name(above[k]));
    r.set_array("tolerance.rows_above_first", named);
    if (above.empty()) {
        info("tolerance {:g}: every row's estimated error is within it (median {:.2g}, 95th percentile {:.2g}, largest "
             "{:.2g})",
             o.tolerance, at(0.5), at(0.95), v.empty() ? 0.0 : *std::max_element(v.begin(), v.end()));
        return;
    }
    const std::string line =
        fmt::format("tolerance {:g}: {} of {} rows have an estimated error above it ({}; median {:.2g}, 95th percentile "
                    "{:.2g}, largest {:.2g}): {}{}",
                    o.tolerance, above.size(), v.size(), refined ? "their budget of rays ran out" : why, at(0.5), at(0.95),
                    *std::max_element(v.begin(), v.end()), named.front(),
                    above.size() > 1 ? fmt::format(" and {} more (the report lists the first 20)", above.size() - 1) : "");
    // Rows that tried and missed are a warning; rows made without trying (hemicube rows, a fixed
    // ray count) are said plainly, as the run's choice.
    if (refined)
        log_warning(line);
    else
        info("{}", line);
}

void report_correction(Report& r, const CorrectedRowProvider& corrected, const RowLedger& ledger, const RowOptions& options) {
    const NearFieldStats& c = corrected.stats();
    r.set("corrections.kind", "near");
    stats::report(r, c);  // every counter of NearFieldStats, by its key
    r.set("corrections.exact_visibility_mode", corrected.corrector().exact_visibility_mode());
    r.set("corrections.far_field", corrected.corrector().far_field_status());
    r.set("corrections.far_field_planes", corrected.corrector().far_field_planes());
    if (const double ns = corrected.corrector().far_field_cost_ns(); std::isfinite(ns))
        r.set("corrections.far_field_estimated_ms_per_row", ns * 1e-6);
    // Per-row error estimate (Σ_j |F_ij − exact_ij|, docs/accuracy.md): every computed row
    // (−1 where not computed), then the largest, the mean and the row that has the largest. Every
    // row's as it came (RowSide, noted in the ledger): this process's, another rank's, or a
    // checkpoint's.
    const std::span<const float> est = ledger.errors();
    std::vector<double> values;
    values.reserve(est.size());
    double mx = 0, sum = 0;
    std::int64_t worst = -1;
    std::uint64_t counted = 0;
    for (std::size_t i = 0; i < est.size(); ++i) {
        values.push_back(std::isnan(est[i]) ? -1.0 : static_cast<double>(est[i]));
        if (std::isnan(est[i])) continue;
        ++counted;
        sum += est[i];
        if (est[i] > mx || worst < 0) {
            mx = est[i];
            worst = static_cast<std::int64_t>(i);
        }
    }
    r.set("row_error_estimate.max", mx);
    r.set("row_error_estimate.mean", counted ? sum / static_cast<double>(counted) : 0.0);
    r.set("row_error_estimate.worst_row", worst);
    r.set_array("row_error_estimate.rows", values);
    report_tolerance(r, corrected, options, ledger.tolerance_errors());
    // How each row was measured (CorrectedRowProvider::RowMeasure): −1 not computed, 0 analytic,
    // 1 centre, 2 sub-hemicubes for a near pair, 3 sub-hemicubes for an occluder beside the sender,
    // 4 sub-hemicubes at 4 × 4 points for an occluder touching it, 5 sub-hemicubes for far pairs
    // not proven unoccluded, 6 measured again by rays (above an asked-for tolerance), 7 drawn
    // again at a finer resolution and no more.
    const std::span<const std::int8_t> measures = ledger.measures();
    r.set_array("corrections.row_measure", std::vector<std::int64_t>(measures.begin(), measures.end()));
}

void report_hemicube(Report& r, const HemicubeRowProvider& provider, const RowDriver& driver) {
    const HemicubeStats st = provider.stats();
    r.set("backend", provider.backend());
    r.set("renderer", provider.renderer());
    r.set("resolution", provider.resolution());
    r.set("threads", provider.threads());
    r.set("workers", provider.workers());
    // Every counter of HemicubeStats by its key: times are CPU-seconds summed over workers;
    // culling is per mesher piece (a face's quad or triangle, drawn whole), summed over hemicubes.
    stats::report(r, st);
    // The enclosure drawn without the depth test (--enclosure on|off): its planes and pieces.
    r.set("drawn.enclosure_planes", provider.enclosure_planes());
    r.set("drawn.enclosure_pieces", provider.enclosure_pieces());
    const double h = st.hemicubes ? static_cast<double>(st.hemicubes) : 1.0;
    r.set("coverage.mean_miss_fraction", st.miss_weight() / h);
    r.set("coverage.mean_back_face_fraction", st.back_face_weight() / h);
    // Rows planned at 4 × 4 ray-cast instead (--fine-rows) and their rays (fine_rows.cast, above).
    r.set("fine_rows.by", driver.fine_rows_by_rays() ? "rays" : "hemicubes");
    r.set("fine_rows.rays_per_row", driver.fine_row_rays());
}

}  // namespace

void report_rates(Report& r, const RowSource& rows, std::size_t patches, double seconds) {
    const double s = std::max(seconds, 1e-9);
    r.set("rows_per_second", static_cast<double>(patches) / s);
    if (const HemicubeRowProvider* h = rows.hemicube()) r.set("hemicubes_per_second", static_cast<double>(h->stats().hemicubes) / s);
}

void report_row_source(Report& r, const RowSource& rows) {
    r.set("method", std::string(to_string(rows.options().method)));
    if (!rows.options().method_choice.empty()) r.set("method_choice", rows.options().method_choice);
    // With a --cost-model file, the engine per row class and the costs weighed (ms of one worker a
    // row; pipeline/row_engine.hpp): --method auto's whole-scene choice, then the 4 × 4 rows' in a
    // hemicube run. Centre and 2 × 2 rows are drawn in a hemicube run, cast in a ray-cast one.
    if (const RowOptions& o = rows.options(); !o.cost_model.builtin()) {
        r.set("method_cost.model", o.cost_model.source);
        if (!o.method_choice.empty()) {  // --method auto's whole-scene choice
            const MethodCosts& c = o.method_costs;
            r.set("method_cost.scene_row_hemicubes", c.hemicubes);
            r.set("method_cost.scene_row_hemicube_ms", 1e-6 * c.hemicube_ns);
            r.set("method_cost.scene_row_rays_ms", 1e-6 * c.rays_ns);
        }
        const bool cast = o.method == RowMethod::Raycast;
        r.set("method_cost.rows_centre", cast ? "rays" : "hemicube");
        r.set("method_cost.rows_2x2", cast ? "rays" : "hemicube");
        if (const RowDriver* d = rows.driver()) {
            const SceneFacts& f = d->facts();
            r.set("method_cost.rows_4x4", d->fine_rows_by_rays() ? "rays" : "hemicube");
            r.set("method_cost.rows_4x4_hemicube_ms",
                  1e-6 * hemicube_row_ns(f.costs, RowProvider::RowPlan::sampled_fine, f.resolution, f.pieces));
            r.set("method_cost.rows_4x4_rays_ms", 1e-6 * ray_row_ns(f.costs, d->fine_row_rays()));
        } else {
            r.set("method_cost.rows_4x4", cast ? "rays" : "hemicube");
        }
    }
    r.set("time.setup", rows.setup_seconds());
    if (const CorrectedRowProvider* c = rows.corrected()) {
        if (rows.hemicube()) {
            const CostModel& m = rows.options().cost_model;
            r.set("cost_model.source", m.builtin() ? std::string("built-in") : m.source);
            r.set("cost_model.pixel_ns", m.pixel_ns);
            r.set("cost_model.cpu_scale", m.cpu_scale);
            r.set("cost_model.piece_ns", m.piece_ns);
            r.set("cost_model.ray_ns", m.ray_ns);
        }
        report_correction(r, *c, rows.ledger(), rows.options());
        const NearFieldStats& s = c->stats();
        if (c->corrector().exact_visibility_mode() == "auto" && (s.exact_visibility > 0 || s.exact_visibility_over_budget > 0))
            info("exact visibility (auto; off: --exact-visibility off): {} near pairs exact past their occluders in {} rows "
                 "({} point evaluations), {} left to sub-hemicubes by the per-row budget",
                 s.exact_visibility, s.exact_visibility_rows, s.exact_visibility_points, s.exact_visibility_over_budget);
        // The analytic kernels' work (geometry/analytic.hpp), summed over this process: every
        // call has a budget, and a fallback is a panel accepted at its fixed rule's value when
        // the budget was spent (its error is within the call's stated bound).
        const AnalyticStats a = analytic_stats();
        stats::report(r, a);
        if (a.fallback_calls > 0)
            info("analytic form factors: {} of {} calls spent their budget and took the fallback rule on {} panels",
                 a.fallback_calls, a.calls, a.fallbacks);
    }
    if (const RaycastRowProvider* rc = rows.raycast()) {
        const RaycastStats s = rc->stats();
        if (rc->tolerance() > 0) {  // refined to the tolerance: rays per row vary
            const RayBudget b = tolerance_rays(rc->tolerance());
            r.set("rays_per_patch_least", b.least);
            r.set("rays_per_patch_most", b.most);
            r.set("rays_per_patch_mean",
                  s.refined_rows ? static_cast<double>(s.rays_traced) / static_cast<double>(s.refined_rows) : 0.0);
            r.set("rows_at_ray_budget", s.rows_at_budget);
        } else {
            r.set("rays_per_patch", rc->rays());
        }
        stats::report(r, s);  // rays_traced
        r.set("threads", rc->threads());
    }
    if (const HemicubeRowProvider* h = rows.hemicube()) report_hemicube(r, *h, *rows.driver());
}

void report_matrix_stats(Report& report, std::uint64_t nnz, const RowSumStats& row_sums,
                         const ReciprocityStats& reciprocity) {
    report.set("nnz", nnz);
    report.set("row_sums.min", row_sums.min);
    report.set("row_sums.max", row_sums.max);
    report.set("row_sums.mean", row_sums.mean);
    report.set("reciprocity.patch_max_abs", reciprocity.patch_max_abs);
    report.set("reciprocity.object_max_rel", reciprocity.object_max_rel);
}

MatrixChecks report_matrix_checks(Report& report, const CsrMatrix& F, const Scene& scene, bool progress) {
    MatrixChecks c;
    c.row_sums = row_sum_stats(F);
    {
        Progress bar("reciprocity", F.size(), progress);
        c.reciprocity = reciprocity_stats(F, scene, &bar);
    }
    report_matrix_stats(report, F.nnz(), c.row_sums, c.reciprocity);
    return c;
}

}  // namespace ffcube
