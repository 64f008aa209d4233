// --enforce on the finished rows, out of core (pipeline/form_factors.hpp's one path).
#include "ffcube/pipeline/enforcement.hpp"

#include <fmt/format.h>

#include <cmath>
#include <cstdlib>
#include <memory>
#include <string_view>
#include <string>
#include <vector>

#include "ffcube/accuracy/enforce.hpp"
#include "ffcube/core/error.hpp"
#include "ffcube/core/log.hpp"
#include "ffcube/core/progress.hpp"
#include "ffcube/core/timer.hpp"
#include "ffcube/io/ffm.hpp"
#include "ffcube/io/transpose_scratch.hpp"
#include "ffcube/scene/patch_areas.hpp"

namespace ffcube {
ClosureEvidence closure_evidence(const RowSource& rows) {
    ClosureEvidence evidence;
    if (rows.hemicube()) evidence.hemicube_miss_weight = rows.hemicube()->stats().miss_weight();
    if (rows.corrected()) evidence.inner_row_sum_min = rows.corrected()->stats().inner_row_sum_min;
    return evidence;
}

namespace {

void report_enforcement(Report& report, const std::string& what, const EnforceStats& st, double seconds) {
    report.set("enforce.mode", what);
    for (const auto& [when, f] : {std::pair{"before", st.before}, std::pair{"after", st.after}}) {
        report.set(fmt::format("enforce.{}.row_sum_min", when), f.row_sum_min);
        report.set(fmt::format("enforce.{}.row_sum_max", when), f.row_sum_max);
        report.set(fmt::format("enforce.{}.reciprocity_max", when), f.reciprocity_max);
    }
    report.set("enforce.iterations", st.iterations);
    report.set("enforce.seconds", seconds);
    info("--enforce {}: row sums {:.6f}..{:.6f} -> {:.6f}..{:.6f}, reciprocity {:.2e} -> {:.2e} (in double; stored as float)",
         what, st.before.row_sum_min, st.before.row_sum_max, st.after.row_sum_min, st.after.row_sum_max,
         st.before.reciprocity_max, st.after.reciprocity_max);
}

// Closure's scaling iterations, each a pass over G: a line per iteration (at most one every 2 s,
// every one under FFCUBE_PROGRESS=always) with the largest |row sum - 1|, and, from the last
// ratio of that error (the iteration converges linearly), the iterations left and their time.
ClosureIterationFn closure_progress(bool progress, const std::string& what) {
    if (!progress) return {};
    struct State {
        Stopwatch since_first, since_line;  // since_first: restarted at the first iteration
        unsigned first = 0;
        double previous = 0;
        bool printed = false;
    };
    auto st = std::make_shared<State>();
    const char* env = std::getenv("FFCUBE_PROGRESS");
    const bool always = env && std::string_view(env) == "always";
    return [st, what, always](unsigned it, double worst, double target) {
        if (st->previous == 0) {
            st->since_first.restart();
            st->first = it;
        }
        const double ratio = st->previous > 0 ? worst / st->previous : 0.0;
        st->previous = worst;
        const bool done = worst <= target;
        if (!always && !done && st->since_line.seconds() < 2.0) return;
        if (!always && done && !st->printed) return;  // short: the summary line says it
        st->since_line.restart();
        st->printed = true;
        const double per = it > st->first ? st->since_first.seconds() / (it - st->first) : 0.0;  // s an iteration
        std::string eta = "ETA soon known";
        if (done) {
            eta = "converged";
        } else if (ratio > 0 && ratio < 1 && per > 0) {
            const double left = std::ceil(std::log(target / worst) / std::log(ratio));
            eta = fmt::format("about {:.0f} more, ETA {:.0f} s", left, left * per);
        }
        info("--enforce {}: scaling iteration {} (a pass over G): max |row sum - 1| {:.2e}, target {:.0e}; {}", what,
             it + 1, worst, target, eta);
    };
}

}  // namespace

// A refusal of enforcement that a .vs3's encl=1 asked for (RowOptions::enforce_origin) names the
// file and its C line: the user may never have written --enforce.
template <class F>
auto naming_origin(const RowOptions& o, F&& f) {
    if (o.enforce_origin.empty()) return f();
    try {
        return f();
    } catch (const InputError& e) {
        throw InputError(fmt::format("{} (View3D's enclosure key: rows made to sum to 1, as --enforce closure, "
                                     "which the command line did not give): {}",
                                     o.enforce_origin, e.what()));
    }
}

void refuse_enforcement_with_obstructions(EnforceRequest request, const Scene& scene) {
    if (request == EnforceRequest::None || enforce_mode(request) != EnforceMode::Closure || !scene.drawn) return;
    throw InputError(fmt::format("--enforce {} (or a .vs3's encl=1): {} has obstruction-only surfaces (O), which "
                                 "absorb energy without rows or columns, so its rows cannot sum to 1",
                                 to_string(request), scene.source));
}

EnforcementFigures apply_enforcement(const RowOptions& options, const RowPass& raw, const RowStreamChecks& raw_checks,
                                     std::span<const double> raw_row_sums, const Scene& scene,
                                     const ClosureEvidence& evidence, const std::filesystem::path& scratch_dir,
                                     std::uint64_t budget_bytes, bool progress,
                                     const std::function<void(std::uint32_t, RowView)>& sink, Report& report) {
    const EnforceRequest request = options.enforce;
    FFCUBE_CHECK(request != EnforceRequest::None);
    const std::string what(to_string(request));
    const EnforceMode mode = enforce_mode(request);
    if (mode == EnforceMode::Closure) naming_origin(options, [&] {
        refuse_enforcement_with_obstructions(request, scene);
        require_closed_scene(what, evidence, raw_row_sums);
    });
    const std::vector<double> areas = patch_areas(scene);
    const auto n = static_cast<std::uint32_t>(scene.size());
    Stopwatch watch;
    EnforcementFigures s;

    // 8 bytes per entry of a band (a u32 row and a float value).
    const TransposePlan plan = plan_transpose(raw_checks.col_counts(), std::max<std::uint64_t>(1, budget_bytes / 8));
    s.bands = plan.band_count();
    ScratchRows g(scratch_dir / "G", budget_bytes);
    EnforcePasses passes;
    passes.rows_and_columns = [&](const RowColumnFn& f) {
        Progress bar(fmt::format("--enforce {}: rows with columns ({} pass{}, {} band{})", what, plan.passes,
                                 plan.passes == 1 ? "" : "es", s.bands, s.bands == 1 ? "" : "s"),
                     std::uint64_t(n) * plan.passes, progress);
        const TransposeFigures t = for_each_row_and_column(raw, raw_checks.col_counts(), plan, scratch_dir, f, &bar);
        s.passes += t.passes;
        s.scratch_bytes += t.scratch_bytes;
    };
    passes.store_g = [&](std::uint32_t, std::span<const std::uint32_t> col, std::span<const double> val) {
        g.append(col, val);
    };
    passes.iteration = closure_progress(progress, what);
    bool converged = false;
    const ClosureIterationFn lines = passes.iteration;
    passes.iteration = [&](unsigned it, double worst, double target) {
        converged = worst <= target;
        if (lines) lines(it, worst, target);
    };
    passes.stored_g = [&](const GRowFn& f) {
        ++s.g_passes;
        // The pass after convergence writes the enforced rows; the others are iterations (above).
        Progress bar(converged ? fmt::format("--enforce {}: writing the enforced rows (a pass over G)", what)
                               : fmt::format("--enforce {}: scaling iteration {} (a pass over G)", what, s.g_passes),
                     n, progress);
        g.for_each([&](std::uint32_t i, std::span<const std::uint32_t> col, std::span<const double> val) {
            f(i, col, val);
            bar.add();
        });
    };
    std::vector<float> fval;
    const EnforcedRowFn out = [&](std::uint32_t i, std::span<const std::uint32_t> col, std::span<const double> val,
                                  std::span<const double> mirror) {
        fval.resize(col.size());
        const double ai = areas[i];
        for (std::size_t k = 0; k < col.size(); ++k) {
            fval[k] = static_cast<float>(val[k]);  // as EnforcedMatrix::to_csr rounds
            const double aj = areas[col[k]];
            const double fji = static_cast<float>(mirror[k]);
            // reciprocity_stats's expression on the float matrix.
            s.patch_max_abs = std::max(s.patch_max_abs,
                                       std::abs(ai * static_cast<double>(fval[k]) - aj * fji) / (0.5 * (ai + aj)));
        }
        sink(i, RowView{col, fval});
    };
    EnforceStats st;
    naming_origin(options, [&] { enforce_passes(n, areas, mode, passes, out, st); });
    s.g_on_disk = g.on_disk();
    s.scratch_bytes += g.bytes();
    report_enforcement(report, what, st, watch.seconds());
    report.set("enforce.passes", s.passes);
    report.set("enforce.bands", s.bands);
    report.set("enforce.g_passes", s.g_passes);
    report.set("enforce.scratch_bytes", s.scratch_bytes);
    return s;
}

}  // namespace ffcube
