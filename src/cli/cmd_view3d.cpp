// ffcube view3d IN.vs3 OUT: a drop-in for NIST View3D's `View3D IN OUT` (docs/urban.md). Every
// surface is one row (as --no-subdivide), reciprocal as View3D's (one exchange area per pair:
// --enforce reciprocity), and the file's control keys decide the rest: out (0 text, 1 binary, 2
// the forks' sparse text), encl (closure), emit, maxD; row and col (View3D's debugging run) are
// refused naming the line. `ffcube-view3d IN OUT` (src/cli/ffcube_view3d/main.cpp, built and
// installed beside ffcube) runs this command, so that a pipeline's VIEW3D_EXE can name it.
#include <fmt/format.h>

#include <memory>
#include <string>
#include <string_view>

#include "cli/commands.hpp"
#include "cli/common.hpp"
#include "ffcube/core/log.hpp"
#include "ffcube/core/timer.hpp"
#include "ffcube/io/report.hpp"
#include "ffcube/pipeline/enforcement.hpp"
#include "ffcube/pipeline/form_factors.hpp"
#include "ffcube/pipeline/row_source.hpp"
#include "ffcube/pipeline/scene_loading.hpp"
#include "ffcube/pipeline/surface_outputs.hpp"
#include "ffcube/scene/load_model.hpp"

namespace ffcube::cli {
namespace {

struct Options {
    std::string input, output;
    bool quiet = false;
};

int run(const Options& o) {
    check_output_path("OUT", o.output);  // before any work
    Stopwatch total;
    Report report;
    report.set("command", "view3d");
    SceneOptions so;
    so.path = o.input;
    so.format = SceneFormat::View3d;  // whatever the name ends in, as View3D reads it
    so.subdivide = false;             // every surface one row, as View3D
    const Scene scene = load_and_mesh(so, report);
    // The rows of `ffcube formfactors IN --no-subdivide` (the command line's defaults: --method auto).
    RowOptions defaults;
    defaults.method_auto = true;
    defaults.tolerance = kDefaultTolerance;  // the file's eps sets it (apply_view3d_controls)
    validate(defaults);
    RowOptions row_options = resolve_row_method(defaults, scene.drawn_scene());
    apply_view3d_controls(scene, row_options, report, /*drop_in=*/true);  // encl=1: closure; row/col refused
    // View3D computes one exchange area A_n F(n→m) per pair and writes both directions from it, so
    // its factors are reciprocal by construction; here the two measured directions are averaged
    // into one (--enforce reciprocity: G = (A_i F_ij + A_j F_ji) / 2), unless encl=1 asked for
    // closure, which implies it.
    if (row_options.enforce == EnforceRequest::None) row_options.enforce = EnforceRequest::Reciprocity;
    refuse_enforcement_with_obstructions(row_options.enforce, scene);
    RowSource rows = make_row_source(scene, row_options);
    for (const std::string& line : describe(rows)) info("{}", line);
    // Every row through the one path (pipeline/form_factors.hpp), cut at maxD as it comes, into memory:
    // View3D's table needs the whole matrix.
    LocalRowFeed feed(rows, nullptr, !o.quiet);
    FormFactorOptions fo;
    fo.max_distance = scene.view3d.max_distance;
    fo.progress = !o.quiet;
    CsrMatrixSink matrix(static_cast<std::uint32_t>(scene.size()));
    MatrixSink* sinks[] = {&matrix};
    const double seconds = compute_form_factors(scene, rows, feed, fo, sinks, report).seconds;
    const CsrMatrix& F = matrix.matrix();
    write_view3d_output(o.output, F, scene, scene.view3d.out, report);
    info("{}: {} surfaces ({} rows in {:.2f} s), View3D {} output; {:.2f} s in all", o.output,
         scene.objects.size() + scene.view3d.masks.size(), scene.size(), seconds,
         scene.view3d.out == 2 ? "sparse text (out=2)" : scene.view3d.out == 1 ? "binary (out=1)" : "text (out=0)",
         total.seconds());
    return 0;
}

}  // namespace

void add_view3d_command(CLI::App& app, std::function<int()>& action) {
    auto opts = std::make_shared<Options>();
    CLI::App* sub = app.add_subcommand(
        "view3d", "View3D's own run: IN.vs3 to OUT in the file's out format (also `ffcube-view3d IN OUT`; docs/urban.md)");
    sub->add_option("IN", opts->input, "View3D input (.vs3, geometry format 3; control keys out, encl, emit, maxD)")
        ->required()
        ->check(CLI::ExistingFile);
    sub->add_option("OUT", opts->output, "view-factor file: out=0 text, 1 binary, 2 sparse text lines \"i j F\"")->required();
    sub->add_flag("-q,--quiet", opts->quiet, "no progress or summary on stderr (warnings and errors still)");
    sub->callback([opts, &action] {
        action = [opts] {
            if (opts->quiet) set_log_level(LogLevel::Quiet);
            return run(*opts);
        };
    });
}

}  // namespace ffcube::cli
