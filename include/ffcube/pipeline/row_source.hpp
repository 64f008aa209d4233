// The one composition root of the row pipeline: from a scene and RowOptions to the RowProvider
// every front end uses (command line, bench, viewer, Python), and the figures it reports.
//
//   request ─► CorrectedRowProvider (--correct near: plans each row, asks the inner provider
//              for the rows that need a measurement, corrects them) ─► HemicubeRowProvider
//              (hemicubes on GL workers) or RaycastRowProvider (rays through Embree) ─► sink
//
// docs/architecture.md follows one row along that path.
#pragma once

#include <memory>
#include <span>
#include <string>
#include <vector>

#include "ffcube/accuracy/enforce.hpp"
#include "ffcube/accuracy/near_field.hpp"
#include "ffcube/formfactor/checks.hpp"
#include "ffcube/formfactor/row_ledger.hpp"
#include "ffcube/formfactor/sparse.hpp"
#include "ffcube/gl/hemicube_provider.hpp"
#include "ffcube/io/ffm.hpp"
#include "ffcube/io/report.hpp"
#include "ffcube/pipeline/options.hpp"
#include "ffcube/pipeline/row_engine.hpp"
#include "ffcube/raycast/raycast_provider.hpp"
#include "ffcube/scene/scene.hpp"

namespace ffcube {

// Hemicube rows above an asked-for tolerance are drawn again at 2N and 4N, at most this (the
// atlas of a 2048 hemicube is 2048 x 4096 pixels), before the rays.
inline constexpr int kMaxRefinedResolution = 2048;

// Where rows come from: hemicubes on a GL context, or rays through Embree, wrapped by the
// near-field correction when it is on. Movable; the scene must outlive it.
class RowSource {
public:
    RowSource() = default;
    RowSource(RowSource&&) noexcept = default;
    RowSource& operator=(RowSource&&) noexcept = default;
    ~RowSource();

    // What the rows are asked of: the correction when on, else the measuring provider.
    RowProvider& provider();
    const RowOptions& options() const { return options_; }
    // The parts; null where the options did not ask for them.
    HemicubeRowProvider* hemicube() const { return hemicube_.get(); }
    // Around the hemicube: which engine measures each row (pipeline/row_engine.hpp).
    RowDriver* driver() const { return driver_.get(); }
    RaycastRowProvider* raycast() const { return raycast_.get(); }
    CorrectedRowProvider* corrected() const { return corrected_.get(); }
    // The side figures (RowSide: obstructed share, estimates, measure) of every row provider()
    // handed out, and of every row compute_form_factors was fed (another rank's, a checkpoint's):
    // for the report's per-row figures. Sized to the radiating scene.
    const RowLedger& ledger() const;
    RowLedger& ledger();
    // Wall seconds spent starting it (GL contexts, worker processes, Embree, near-field setup).
    double setup_seconds() const { return setup_seconds_; }

private:
    friend RowSource make_row_source(const Scene& scene, const RowOptions& options);
    friend void rebind_row_source(RowSource& rows, const Scene& scene);
    void wrap(const Scene& radiating);  // the correction and the obstruction cut around the measuring provider
    RowOptions options_;
    // Order matters: the correction holds a reference to the measuring provider, so it is
    // declared last (destroyed first).
    std::unique_ptr<HemicubeRowProvider> hemicube_;
    std::unique_ptr<RaycastRowProvider> raycast_;
    std::unique_ptr<RowDriver> driver_;  // with hemicube_; refers to it and to the scene
    // Hemicube rows above an asked-for tolerance, measured again by rays refined to it
    // (refine_hemicube_rows; built on its first row: the hemicube's workers fork first).
    std::unique_ptr<RowProvider> refiner_;
    // Before the rays, the same rows drawn again at 2N and 4N (kMaxRefinedResolution at most).
    std::vector<std::unique_ptr<RowProvider>> redrawers_;
    std::unique_ptr<CorrectedRowProvider> corrected_;
    // With obstruction-only surfaces: the radiating rows, cut to the radiating columns; holds a
    // reference to the providers above, so it is declared after them.
    std::unique_ptr<LeadingRowProvider> leading_;
    // Outermost: notes each row's side figures in ledger_ on its way out.
    std::unique_ptr<RowLedger> ledger_;
    std::unique_ptr<RowProvider> noting_;
    double setup_seconds_ = 0;
};

// Whether hemicube rows whose estimate is above the tolerance are measured again by the ray
// caster refined to it (CorrectedRowProvider::refine_with): a target asked for (--tolerance, a
// .vs3's eps, Python's tolerance=), the hemicube, the near-field correction, no fixed ray count.
bool refine_hemicube_rows(const RowOptions& o);

// Validates the options (InputError) and starts the provider they name, on the scene as drawn
// (Scene::drawn_scene(): obstruction-only surfaces included, their rows never asked for and their
// columns cut). Start it before this
// process makes a GL context of its own, so that hemicube workers can be forked processes.
RowSource make_row_source(const Scene& scene, const RowOptions& options);

// Points `rows` at another scene (the next adaptive level's elements) with the same options,
// keeping its hemicube workers (forked processes stay; HemicubeRowProvider::set_scene): the rows
// are the same bits as make_row_source(scene, rows.options())'s. The ray caster and the near-field
// correction are made again for the new scene (they hold no workers). setup_seconds() is then
// this call's time. The same rules on `scene` as make_row_source.
void rebind_row_source(RowSource& rows, const Scene& scene);

// One line per part, saying what it runs on ("hemicube on egl (llvmpipe), 2 threads, ...").
std::vector<std::string> describe(const RowSource& rows);

// How rows are made, as recorded in .ffm files and checkpoints (deterministic settings only:
// not threads, not the backend). Same options, same metadata, so a resumed run refuses rows
// made differently.
FfmMetadata row_metadata(const RowOptions& options);

// The provider's figures into the report: method and setup time; backend, renderer, resolution,
// workers, time split and culling for hemicubes; rays for the ray caster; the correction's
// counts and per-row error estimates.
void report_row_source(Report& report, const RowSource& rows);

// The run's rates over its row phase of `seconds`: rows_per_second (every method) and, for the
// hemicube, this process's hemicubes drawn per second (sub-hemicubes one each). Before 2026-12-05
// `hemicubes_per_second` held the rows' figure.
void report_rates(Report& report, const RowSource& rows, std::size_t patches, double seconds);

// --enforce on the finished rows: apply_enforcement (pipeline/enforcement.hpp), in the one path of
// pipeline/form_factors.hpp.

// The checks every front end reports on a finished matrix: "nnz", "row_sums.{min,max,mean}" and
// "reciprocity.{patch_max_abs,object_max_rel}" (reciprocity with a progress bar when `progress`).
struct MatrixChecks {
    RowSumStats row_sums;
    ReciprocityStats reciprocity;
};
MatrixChecks report_matrix_checks(Report& report, const CsrMatrix& F, const Scene& scene, bool progress);
// The keys report_matrix_checks sets (nnz, row_sums.*, reciprocity.*), from statistics computed
// elsewhere (the streamed .ffm path computes them from the stream and the file).
void report_matrix_stats(Report& report, std::uint64_t nnz, const RowSumStats& row_sums,
                         const ReciprocityStats& reciprocity);

}  // namespace ffcube
