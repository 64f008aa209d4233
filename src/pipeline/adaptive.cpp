// Adaptive meshing: the loop of solves on refined scenes (pipeline/adaptive.hpp, docs/adaptive.md).
#include "ffcube/pipeline/adaptive.hpp"

#include <fmt/format.h>
#include <glm/common.hpp>

#include <algorithm>
#include <cmath>
#include <optional>

#include "ffcube/core/error.hpp"
#include "ffcube/core/timer.hpp"
#include "ffcube/scene/refine.hpp"
#include "ffcube/solver/refinement.hpp"
#include "row_reuse.hpp"

namespace ffcube {
namespace {

std::vector<Vec3> object_means(const Scene& scene, std::span<const Vec3> radiosity) {
    std::vector<Vec3> out;
    for (const ObjectRadiosity& o : object_radiosity(scene, radiosity)) out.push_back(o.radiosity);
    return out;
}

double max_channel(const Vec3& v) { return std::max({v.r, v.g, v.b}); }

// One level's variation as per-object errors: the area-weighted mean over the object's patches of
// the luminance variation, spread over the channels in proportion to the object's radiosity.
std::vector<ObjectError> object_errors_from_variation(const Scene& scene, std::span<const Vec3> radiosity) {
    const std::vector<double> variation = radiosity_variation(scene, radiosity);
    const std::vector<ObjectRadiosity> objects = object_radiosity(scene, radiosity);
    std::vector<double> weighted(objects.size(), 0.0);
    for (std::size_t i = 0; i < scene.size(); ++i) weighted[scene.patches[i].object] += scene.patches[i].area * variation[i];
    std::vector<ObjectError> out;
    for (std::size_t o = 0; o < objects.size(); ++o) {
        ObjectError e;
        e.name = objects[o].name;
        e.radiosity = objects[o].radiosity;
        const double y = radiosity_luminance(e.radiosity);
        if (objects[o].area > 0.0 && y > 0.0) e.error = (weighted[o] / objects[o].area / y) * e.radiosity;
        const double m = max_channel(e.radiosity);
        e.relative = m > 0.0 ? max_channel(e.error) / m : 0.0;
        out.push_back(e);
    }
    return out;
}

}  // namespace

void validate(const AdaptiveOptions& o) {
    if (!(o.target_error > 0.0 && std::isfinite(o.target_error)))
        throw InputError(fmt::format("--target-error {}: must be a finite number > 0 (relative, e.g. 1e-3)", o.target_error));
    if (o.max_elements < 1) throw InputError("--max-elements 0: must be at least 1");
    if (o.max_levels < 1) throw InputError("adaptive meshing needs at least one refinement level");
    if (o.factor < 2 || o.factor > 8) throw InputError(fmt::format("split factor {}: must be 2..8", o.factor));
    if (!(o.fraction > 0.0 && o.fraction <= 1.0))
        throw InputError(fmt::format("marked fraction {}: must be in (0, 1]", o.fraction));
}

std::vector<ObjectError> object_errors_between_levels(const Scene& scene, std::span<const Vec3> fine_objects,
                                                      std::span<const Vec3> coarse_objects, std::span<const double> refined,
                                                      std::span<const ObjectError> previous) {
    FFCUBE_CHECK(fine_objects.size() == scene.objects.size() && coarse_objects.size() == fine_objects.size());
    FFCUBE_CHECK(refined.size() == fine_objects.size() && previous.size() == fine_objects.size());
    std::vector<ObjectError> out;
    for (std::size_t o = 0; o < fine_objects.size(); ++o) {
        ObjectError e;
        e.name = scene.objects[o];
        e.radiosity = fine_objects[o];
        const double phi = std::clamp(refined[o], 0.0, 1.0);
        if (phi > 0.0) {
            e.error = glm::abs(fine_objects[o] - coarse_objects[o]) * (2.0 / phi - 1.0);
            const double m = max_channel(e.radiosity);
            e.relative = m > 0.0 ? max_channel(e.error) / m : 0.0;
        } else {  // not refined: what was estimated before
            e.error = previous[o].error;
            e.relative = previous[o].relative;
        }
        out.push_back(e);
    }
    return out;
}

struct AdaptiveRun::Impl {
    RowOptions row_options;
    SolverOptions solver;
    AdaptiveOptions options;
    std::function<void(const std::string&)> progress;
    AdaptiveResult a;
    // Rows of the previous level, its split factors and each element's patch in it: the rows of the
    // patches not split are carried over (row_reuse.hpp) unless options.reuse_rows is off.
    LevelRows carried;
    std::vector<std::uint32_t> parent, split;
    std::vector<double> refined_share;  // per object: the share of its area the last refinement split
    std::unique_ptr<ReusedRowProvider> provider;
    std::uint32_t level = 0;
    Stopwatch watch;  // since the current level began
    bool done = false;
    // Made by finish_level, installed by next_level: the next level's elements and their origins.
    std::optional<Scene> next_scene;
    std::vector<std::uint32_t> next_origin;

    void begin_level();
    void record(const SolveResult& result);
    bool estimate();  // false: the run stops here
    bool refine();    // false: nothing to refine; else next_scene and next_origin are set
};

void AdaptiveRun::Impl::begin_level() {
    watch.restart();
    provider.reset();  // it refers to the previous level's rows
    if (level > 0 && options.keep_workers) {
        rebind_row_source(a.rows, *a.scene);  // the same workers, this level's elements
    } else {
        a.rows = RowSource{};  // the previous level's workers end before the next start
        a.rows = make_row_source(*a.scene, row_options);
    }
    provider = std::make_unique<ReusedRowProvider>(*a.scene, a.rows.provider(), parent, split,
                                                   options.reuse_rows ? std::move(carried) : LevelRows{});
}

void AdaptiveRun::Impl::record(const SolveResult& result) {
    a.result = result;
    carried = provider->take_rows();
    AdaptiveLevel rec;
    rec.elements = a.scene->size();
    rec.rows_computed = provider->rows_measured();
    rec.rows_reused = provider->rows_reused();
    rec.objects = object_means(*a.scene, a.result.radiosity);
    rec.seconds = watch.seconds();
    rec.setup_seconds = a.rows.setup_seconds();
    a.levels.push_back(rec);
}

bool AdaptiveRun::Impl::estimate() {
    if (!a.result.converged()) {
        a.stop = "unconverged_solve";
        return false;
    }
    const AdaptiveLevel& rec = a.levels.back();
    if (level == 0) {
        a.error_basis = "variation";
        a.objects = object_errors_from_variation(*a.scene, a.result.radiosity);
    } else {
        a.error_basis = "levels";
        a.objects = object_errors_between_levels(*a.scene, rec.objects, a.levels[level - 1].objects, refined_share, a.objects);
    }
    a.max_relative_error = 0.0;
    for (const ObjectError& e : a.objects) a.max_relative_error = std::max(a.max_relative_error, e.relative);
    if (progress)
        progress(fmt::format("adaptive level {}: {} elements, {} rows measured, {} reused, {:.2f} s, largest estimated object error {:.3g} ({})",
                             level, rec.elements, rec.rows_computed, rec.rows_reused, rec.seconds, a.max_relative_error, a.error_basis));
    if (level > 0 && a.max_relative_error <= options.target_error) {
        a.stop = "target";
        a.reached_target = true;
        return false;
    }
    if (level == options.max_levels) {
        a.stop = "level_limit";
        return false;
    }
    return true;
}

bool AdaptiveRun::Impl::refine() {
    // Refine the objects whose estimated error is over the target, each by its own bulk criterion.
    std::vector<bool> over(a.scene->objects.size(), false);
    for (std::size_t o = 0; o < a.objects.size(); ++o) over[o] = a.objects[o].relative > options.target_error;
    const RefinementChoice choice = choose_refinement(*a.scene, a.result.radiosity, options.target_error, options.max_elements,
                                                      options.factor, options.fraction, over);
    a.levels.back().candidates = choice.candidates;
    if (choice.marked == 0) {
        // Nothing varies by more than the target: at level 0 the variation is the estimate.
        a.stop = choice.candidates == 0 ? "nothing_to_refine" : "element_budget";
        a.reached_target = choice.candidates == 0 && a.max_relative_error <= options.target_error;
        return false;
    }
    a.levels.back().refined = choice.marked;
    RefinedScene refined = refine_patches(*a.scene, choice.split);
    parent = refined.parent;
    split = choice.split;
    refined_share.assign(a.scene->objects.size(), 0.0);
    std::vector<double> object_area(a.scene->objects.size(), 0.0);
    for (std::size_t i = 0; i < a.scene->size(); ++i) {
        const Patch& p = a.scene->patches[i];
        object_area[p.object] += p.area;
        if (choice.split[i] > 1) refined_share[p.object] += p.area;
    }
    for (std::size_t o = 0; o < object_area.size(); ++o) refined_share[o] = object_area[o] > 0.0 ? refined_share[o] / object_area[o] : 0.0;
    next_origin.resize(refined.parent.size());
    for (std::size_t e = 0; e < next_origin.size(); ++e) next_origin[e] = a.origin[refined.parent[e]];
    next_scene = std::move(refined.scene);
    return true;
}

AdaptiveRun::AdaptiveRun(const Scene& start, const RowOptions& rows, const SolverOptions& solver, const AdaptiveOptions& options,
                         std::function<void(const std::string&)> progress)
    : impl_(std::make_unique<Impl>()) {
    validate(options);
    if (start.drawn)  // refine_patches would split the radiating patches only, and lose the obstructions
        throw InputError(fmt::format("adaptive meshing: {} has obstruction-only surfaces (O): not supported yet", start.source));
    if (options.max_elements < start.size())
        throw InputError(fmt::format("--max-elements {}: fewer than the {} patches of the starting mesh", options.max_elements,
                                     start.size()));
    Impl& m = *impl_;
    m.row_options = rows;
    m.solver = solver;
    m.options = options;
    m.progress = std::move(progress);
    m.a.scene = std::make_unique<Scene>(start);
    m.a.origin.resize(start.size());
    for (std::uint32_t i = 0; i < start.size(); ++i) m.a.origin[i] = i;
    m.parent = m.a.origin;
    m.split.assign(start.size(), 1);
    m.begin_level();
}

AdaptiveRun::~AdaptiveRun() = default;

std::uint32_t AdaptiveRun::level() const { return impl_->level; }
const Scene& AdaptiveRun::scene() const { return *impl_->a.scene; }
RowProvider& AdaptiveRun::provider() {
    FFCUBE_CHECK_MSG(impl_->provider, "AdaptiveRun: no level in progress");
    return *impl_->provider;
}
HemicubeRowProvider* AdaptiveRun::hemicube() { return impl_->a.rows.hemicube(); }
std::span<const std::uint32_t> AdaptiveRun::origin() const { return impl_->a.origin; }
const RowSource& AdaptiveRun::rows() const { return impl_->a.rows; }
bool AdaptiveRun::done() const { return impl_->done; }

void AdaptiveRun::step_level() {
    finish_level(solve_radiosity(scene(), provider(), impl_->solver));
    if (!done()) next_level();
}

void AdaptiveRun::finish_level(const SolveResult& result) {
    Impl& m = *impl_;
    FFCUBE_CHECK_MSG(!m.done, "AdaptiveRun::finish_level after the run ended");
    FFCUBE_CHECK(result.radiosity.size() == m.a.scene->size());
    FFCUBE_CHECK_MSG(!m.next_scene, "AdaptiveRun::finish_level twice without next_level");
    m.record(result);
    m.done = !m.estimate() || !m.refine();
}

void AdaptiveRun::next_level() {
    Impl& m = *impl_;
    FFCUBE_CHECK_MSG(m.next_scene, "AdaptiveRun::next_level without a finished level to refine");
    m.provider.reset();  // it refers to the scene replaced now
    *m.a.scene = std::move(*m.next_scene);
    m.next_scene.reset();
    m.a.origin = std::move(m.next_origin);
    ++m.level;
    m.begin_level();
}

AdaptiveResult AdaptiveRun::take_result() {
    FFCUBE_CHECK_MSG(impl_->done, "AdaptiveRun::take_result before the run ended");
    impl_->provider.reset();
    return std::move(impl_->a);
}

AdaptiveResult solve_adaptive(const Scene& start, const RowOptions& rows, const SolverOptions& solver,
                              const AdaptiveOptions& options, const std::function<void(const std::string&)>& progress) {
    AdaptiveRun run(start, rows, solver, options, progress);
    while (!run.done()) run.step_level();
    return run.take_result();
}

void report_adaptive(Report& r, const AdaptiveResult& a, const AdaptiveOptions& o) {
    r.set("adaptive.target_error", o.target_error);
    r.set("adaptive.max_elements", o.max_elements);
    r.set("adaptive.max_levels", o.max_levels);
    r.set("adaptive.factor", o.factor);
    r.set("adaptive.fraction", o.fraction);
    r.set("adaptive.stop", a.stop);
    r.set("adaptive.reached_target", a.reached_target);
    r.set("adaptive.elements", a.scene->size());
    r.set("adaptive.start_patches", a.levels.empty() ? 0 : a.levels.front().elements);
    std::vector<std::uint64_t> elements, refined, candidates, rows, reused;
    std::vector<double> seconds, setup;
    for (const AdaptiveLevel& l : a.levels) {
        setup.push_back(l.setup_seconds);
        elements.push_back(l.elements);
        refined.push_back(l.refined);
        candidates.push_back(l.candidates);
        rows.push_back(l.rows_computed);
        reused.push_back(l.rows_reused);
        seconds.push_back(l.seconds);
    }
    r.set_array("adaptive.levels.elements", elements);
    r.set_array("adaptive.levels.refined", refined);
    r.set_array("adaptive.levels.candidates", candidates);
    r.set_array("adaptive.levels.rows_computed", rows);
    r.set_array("adaptive.levels.rows_reused", reused);
    r.set("adaptive.reuse_rows", o.reuse_rows);
    r.set_array("adaptive.levels.seconds", seconds);
    r.set_array("adaptive.levels.setup_seconds", setup);
    r.set("adaptive.keep_workers", o.keep_workers);
    // Where the refinement went: elements per object.
    std::vector<std::uint64_t> per_object(a.scene->objects.size(), 0);
    for (const Patch& p : a.scene->patches) ++per_object[p.object];
    r.set_array("adaptive.elements_per_object", per_object);
    report_object_errors(r, a.objects, a.error_basis, a.max_relative_error);
}

void report_object_errors(Report& r, std::span<const ObjectError> objects, std::string_view basis, double max_relative) {
    std::vector<std::string> names;
    std::vector<double> rel, er, eg, eb;
    for (const ObjectError& e : objects) {
        names.push_back(e.name);
        rel.push_back(e.relative);
        er.push_back(e.error.r);
        eg.push_back(e.error.g);
        eb.push_back(e.error.b);
    }
    r.set("discretisation_error.basis", basis);
    r.set_array("discretisation_error.objects", names);
    r.set_array("discretisation_error.relative", rel);
    r.set_array("discretisation_error.abs_r", er);
    r.set_array("discretisation_error.abs_g", eg);
    r.set_array("discretisation_error.abs_b", eb);
    r.set("discretisation_error.max_relative", max_relative);
}

std::vector<ObjectError> estimate_object_errors(const Scene& scene, std::span<const Vec3> radiosity) {
    return object_errors_from_variation(scene, radiosity);
}

}  // namespace ffcube
