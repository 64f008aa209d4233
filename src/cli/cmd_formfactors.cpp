// ffcube formfactors: headless precomputation of the form-factor matrix.
#include <fmt/format.h>

#include "cli/commands.hpp"
#include "cli/common.hpp"
#include "ffcube/core/error.hpp"
#include "ffcube/core/log.hpp"
#include "ffcube/core/progress.hpp"
#include "ffcube/core/timer.hpp"
#include "ffcube/formfactor/checks.hpp"
#include "ffcube/io/csv.hpp"
#include "ffcube/io/ffm.hpp"
#include "ffcube/io/mtx.hpp"

namespace ffcube::cli {
namespace {

struct Options {
    SceneOptions scene;
    FormFactorOptions ff;
    std::string output, groups, report;
};

bool ends_with(const std::string& s, std::string_view suffix) {
    return s.size() >= suffix.size() && s.compare(s.size() - suffix.size(), suffix.size(), suffix) == 0;
}

// Records the hemicube provider's figures in the report.
void report_hemicube(Report& r, const HemicubeRowProvider& provider) {
    const HemicubeStats st = provider.stats();
    r.set("backend", provider.backend());
    r.set("renderer", provider.renderer());
    r.set("resolution", provider.resolution());
    r.set("threads", provider.threads());
    r.set("workers", provider.workers());
    r.set("hemicubes", st.hemicubes);
    // CPU-seconds summed over worker threads.
    r.set("time.prepare", st.prepare_seconds);
    r.set("time.drawing", st.draw_seconds);
    r.set("time.readback", st.readback_seconds);
    r.set("time.accumulation", st.accumulate_seconds);
    // Culling is per mesher piece (a face's quad or triangle, drawn whole), summed over hemicubes.
    r.set("left_out.pieces_considered", st.pieces_considered);
    r.set("left_out.pieces_behind_plane", st.pieces_behind);
    const char* names[5] = {"top", "pos_x", "neg_x", "pos_y", "neg_y"};
    for (std::size_t f = 0; f < 5; ++f) {
        r.set(fmt::format("left_out.pieces_culled_per_face.{}", names[f]), st.pieces_culled[f]);
        r.set(fmt::format("drawn.pieces_per_face.{}", names[f]), st.pieces_drawn[f]);
    }
    const double h = st.hemicubes ? static_cast<double>(st.hemicubes) : 1.0;
    r.set("coverage.mean_miss_fraction", st.miss_weight / h);
    r.set("coverage.mean_back_face_fraction", st.back_face_weight / h);
    r.set("self_hits", st.self_hits);
}

int run(const Options& o) {
    const bool ffm = ends_with(o.output, ".ffm"), mtx = ends_with(o.output, ".mtx");
    if (!o.output.empty() && !ffm && !mtx)
        throw InputError(fmt::format("--output {}: the name must end in .ffm (ffcube's format) or .mtx (Matrix Market)", o.output));
    check_output_path("--output", o.output);
    check_output_path("--groups", o.groups);
    check_output_path("--report", o.report);
    const HemicubeOptions hopt = hemicube_options(o.ff);

    Report report;
    report.set("command", "formfactors");
    Scene scene = load_and_mesh(o.scene, report);

    Stopwatch total;
    Stopwatch watch;
    HemicubeRowProvider provider(scene, hopt);
    report.set("time.context_setup", watch.seconds());
    info("{} on {} ({}), {} thread(s), resolution {}", provider.name(), provider.backend(), provider.renderer(),
         provider.threads(), provider.resolution());

    watch.restart();
    CsrMatrix F(static_cast<std::uint32_t>(scene.size()));
    {
        Progress progress("rows", scene.size(), !o.scene.quiet);
        std::vector<std::uint32_t> all(scene.size());
        for (std::uint32_t i = 0; i < all.size(); ++i) all[i] = i;
        provider.compute_rows(all, [&](std::uint32_t, const SparseRow& row) {
            F.append_row(row);
            progress.add();
        });
    }
    const double seconds = watch.seconds();
    report.set("seconds", seconds);
    report.set("hemicubes_per_second", static_cast<double>(scene.size()) / std::max(seconds, 1e-9));
    report.set("nnz", F.nnz());
    report.set("skipped_rows", 0);
    report_hemicube(report, provider);

    const RowSumStats rs = row_sum_stats(F);
    const ReciprocityStats rec = reciprocity_stats(F, scene);
    report.set("row_sums.min", rs.min);
    report.set("row_sums.max", rs.max);
    report.set("row_sums.mean", rs.mean);
    report.set("reciprocity.patch_max_abs", rec.patch_max_abs);
    report.set("reciprocity.object_max_rel", rec.object_max_rel);
    info("{} rows in {:.2f} s ({:.0f} hemicubes/s); row sums {:.6f}..{:.6f} (mean {:.6f}); reciprocity (objects) {:.2e}",
         scene.size(), seconds, static_cast<double>(scene.size()) / std::max(seconds, 1e-9), rs.min, rs.max, rs.mean,
         rec.object_max_rel);

    watch.restart();
    if (ffm) {
        FfmMetadata meta;
        meta.method = "hemicube";
        meta.resolution = static_cast<std::uint32_t>(hopt.resolution);
        meta.settings = fmt::format("rotate={} seed={}", hopt.rotate ? 1 : 0, hopt.seed);
        write_ffm(o.output, F, scene, meta);
    } else if (mtx) {
        write_mtx(o.output, F);
    }
    if (!o.groups.empty()) write_groups_csv(o.groups, object_form_factors(F, scene), scene.objects);
    report.set("time.writing", watch.seconds());
    report.set("time.total", total.seconds());
    if (!o.report.empty()) report.write(o.report);
    return 0;
}

}  // namespace

void add_formfactors_command(CLI::App& app, std::function<int()>& action) {
    auto opts = std::make_shared<Options>();
    CLI::App* sub = app.add_subcommand("formfactors", "compute the form-factor matrix of a scene with hemicubes");
    add_scene_options(*sub, opts->scene);
    add_formfactor_options(*sub, opts->ff);
    sub->add_option("-o,--output", opts->output, "write F to F.ffm (ffcube's binary format) or F.mtx (Matrix Market)");
    sub->add_option("--groups", opts->groups, "write object-to-object form factors as CSV (from,to,F)");
    sub->add_option("--report", opts->report, "write a JSON report (timings, row sums, reciprocity, culling)");
    sub->callback([opts, &action] {
        action = [opts] {
            if (opts->scene.quiet) set_log_level(LogLevel::Quiet);
            return run(*opts);
        };
    });
}

}  // namespace ffcube::cli
