#include "ffcube/pipeline/surface_outputs.hpp"

#include <fmt/format.h>

#include <glm/geometric.hpp>

#include <algorithm>
#include <cctype>

#include "ffcube/core/error.hpp"
#include "ffcube/core/log.hpp"
#include "ffcube/formfactor/checks.hpp"
#include "ffcube/formfactor/sky.hpp"
#include "ffcube/io/fields.hpp"
#include "ffcube/solver/exchange.hpp"

namespace ffcube {

SkyBy parse_sky_by(std::string_view text) {
    if (text == "patch") return SkyBy::Patch;
    if (text == "object") return SkyBy::Object;
    throw InputError(fmt::format("--sky-by {}: expected patch or object", text));
}

FileFormat parse_file_format(std::string_view text) {
    if (text == "auto") return FileFormat::Auto;
    if (text == "text") return FileFormat::Text;
    if (text == "binary") return FileFormat::Binary;
    throw InputError(fmt::format("{}: expected auto, text or binary", text));
}

void apply_view3d_controls(const Scene& scene, RowOptions& rows, Report& report, bool drop_in) {
    const View3dControls& v = scene.view3d;
    if (!v.present) return;
    report.set("view3d.title", v.title);
    report.set("view3d.encl", v.encl);
    report.set("view3d.emit", v.emit);
    report.set("view3d.out", v.out);
    std::vector<std::string> ignored;
    for (const std::string& x : v.ignored) {
        std::string key = x.substr(0, x.find('='));
        std::transform(key.begin(), key.end(), key.begin(), [](unsigned char c) { return std::tolower(c); });
        const bool max_d = key == "maxd";
        if (!(drop_in && max_d)) ignored.push_back(x);  // `ffcube view3d` applies maxD
    }
    report.set_array("view3d.ignored_controls", ignored);
    // eps: View3D's convergence criterion becomes the accuracy target, unless the command line
    // gave one (docs/accuracy.md, "Accuracy by target": the mapping).
    if (v.eps > 0.0) {
        report.set("view3d.eps", v.eps);
        if (!rows.tolerance_given) {
            rows.tolerance = v.eps;
            rows.tolerance_given = true;  // a target asked for, as --tolerance would
            info("{}:{}: eps={}: the accuracy target (--tolerance {})", scene.source, v.eps_line, v.eps, v.eps);
        } else if (rows.tolerance != v.eps) {
            info("{}:{}: eps={} is overridden by --tolerance {}", scene.source, v.eps_line, v.eps, rows.tolerance);
        }
    }
    if (drop_in) {
        // View3D's row=n computes row n alone and writes its N factors one a line (%.5f), with
        // col=m F(n→m) only to its log: a debugging run, not the matrix a pipeline reads.
        if (v.row != 0)
            throw InputError(fmt::format("{}:{}: control row={}: View3D's one-row debugging run is not supported by "
                                         "ffcube view3d (it computes every row): remove the key or set row=0, and read "
                                         "row {} of the output",
                                         scene.source, v.row_line, v.row, v.row));
        if (v.max_distance > 0.0)
            info("{}:{}: maxD={}: pairs of surfaces whose centroids lie farther apart get no factor", scene.source,
                 v.max_distance_line, v.max_distance);
    } else {
        if (v.row != 0)
            log_warning(fmt::format("{}:{}: control row={} is ignored: ffcube computes every row (read one row from the "
                                    "output)",
                                    scene.source, v.row_line, v.row));
        if (v.col != 0)
            log_warning(fmt::format("{}:{}: control col={} is ignored: ffcube computes every column (read one column from "
                                    "the output)",
                                    scene.source, v.col_line, v.col));
        if (v.max_distance > 0.0)
            log_warning(fmt::format("{}:{}: control maxD={} is ignored: only `ffcube view3d` applies the cut-off distance; "
                                    "every pair is computed",
                                    scene.source, v.max_distance_line, v.max_distance));
    }
    if (v.encl != 1) return;
    if (rows.enforce == EnforceRequest::None) {
        rows.enforce = EnforceRequest::Closure;
        rows.enforce_origin = v.encl_line ? fmt::format("{}:{}: encl=1", scene.source, v.encl_line)
                                          : fmt::format("{}: encl=1", scene.source);
        info("{}: encl=1: rows are made to conserve energy (--enforce closure)", scene.source);
        report.set("view3d.encl_applied", "closure");
    } else {
        info("{}: encl=1: --enforce {} given on the command line is used instead", scene.source, to_string(rows.enforce));
        report.set("view3d.encl_applied", std::string(to_string(rows.enforce)));
    }
}

namespace {

// View3D's masking surfaces (M) in its table, as View3D computes them: the base's faces are what
// the masks leave of it (the loader cut them out), so its row is scaled to the whole base area,
// A_rest F(rest → j) / A_base, its area made whole again, and each mask gets a row and a column at
// its place among the surfaces: F(mask → base) = 1, F(base → mask) = A_mask / A_base, 0 elsewhere
// (its front faces the base; what sees its back is blocked, as by an obstruction).
void add_view3d_masks(View3dTable& t, const std::vector<View3dControls::Mask>& masks) {
    std::vector<std::size_t> index(t.area.size());  // object -> its row now
    for (std::size_t i = 0; i < index.size(); ++i) index[i] = i;
    for (const View3dControls::Mask& m : masks) {
        const std::size_t b = index[m.base_object];
        const double rest = t.area[b], whole = rest + m.area;
        for (double& f : t.F[b]) f *= rest / whole;
        t.area[b] = whole;
        const std::size_t at = m.position + static_cast<std::size_t>(&m - masks.data());  // earlier masks came before it
        for (std::size_t& i : index)
            if (i >= at) ++i;
        for (std::vector<double>& row : t.F) row.insert(row.begin() + static_cast<std::ptrdiff_t>(at), 0.0);
        t.F.insert(t.F.begin() + static_cast<std::ptrdiff_t>(at), std::vector<double>(t.area.size() + 1, 0.0));
        t.area.insert(t.area.begin() + static_cast<std::ptrdiff_t>(at), m.area);
        t.emissivity.insert(t.emissivity.begin() + static_cast<std::ptrdiff_t>(at), m.emissivity);
        const std::size_t base_row = index[m.base_object];
        t.F[at][base_row] = 1.0;
        t.F[base_row][at] = m.area / whole;
    }
}

}  // namespace

View3dTable view3d_table(const CsrMatrix& F, const Scene& scene) { return view3d_table(object_form_factors(F, scene), scene); }

View3dTable view3d_table(std::vector<std::vector<double>> object_factors, const Scene& scene) {
    View3dTable t;
    t.area = object_areas(scene);
    t.F = std::move(object_factors);
    std::vector<double> eps(scene.size());
    for (std::size_t i = 0; i < scene.size(); ++i) {
        const Vec3 kd = scene.materials[scene.patches[i].material].kd;
        eps[i] = 1.0 - (kd.x + kd.y + kd.z) / 3.0;
    }
    t.emissivity = object_means(eps, scene);
    add_view3d_masks(t, scene.view3d.masks);
    t.encl = scene.view3d.encl;
    t.emit = scene.view3d.emit;
    if (t.emit == 1) t.F = hottel_exchange_factors(t.F, t.area, t.emissivity);
    return t;
}

namespace {

// The sky statistics (always) and the files that need only the sky view factors and the scene.
// row_error: each row's estimated error (NaN: not computed here), the patch table's last column.
void write_sky_and_table(const SurfaceOutputOptions& o, std::vector<double> svf, const Scene& scene, Report& report,
                         std::span<const double> obstructed, std::span<const float> row_error) {
    std::vector<double> row_sum(svf.size());
    for (std::size_t i = 0; i < svf.size(); ++i) row_sum[i] = 1.0 - svf[i];  // before obstructions are taken off
    if (!obstructed.empty()) {
        FFCUBE_CHECK(obstructed.size() == svf.size());
        for (std::size_t i = 0; i < svf.size(); ++i) svf[i] = std::max(0.0, svf[i] - obstructed[i]);
    }
    const SkyStats s = sky_stats(svf, scene);
    report.set("sky.min", s.min);
    report.set("sky.mean", s.mean);
    report.set("sky.max", s.max);
    report.set("sky.area_weighted_mean", s.area_weighted_mean);
    if (!o.sky.empty()) {
        if (o.sky_by == SkyBy::Patch)
            write_patch_sky_csv(o.sky, scene, svf);
        else
            write_object_sky_csv(o.sky, scene.objects, object_areas(scene), object_means(svf, scene));
    }
    if (!o.patch_table.empty()) write_patch_table(o.patch_table, scene, row_error);
    if (!o.fields.empty()) {
        write_fields(o.fields, scene, {{"sky_view_factor", svf}, {"row_sum", row_sum}});
        report.set("fields.written", o.fields);
    }
}

const char* view3d_format_name(int out) { return out == 2 ? "sparse" : out == 1 ? "binary" : "text"; }

// View3D's file from the object form factors (its surfaces are the objects).
void write_view3d_file(const SurfaceOutputOptions& o, std::vector<std::vector<double>> object_factors,
                       const Scene& scene, Report& report) {
    const int out = o.view3d_format == FileFormat::Binary ? 1
                    : o.view3d_format == FileFormat::Text ? 0
                    : scene.view3d.present                ? scene.view3d.out
                                                          : 0;
    write_view3d(o.view3d, view3d_table(std::move(object_factors), scene), out);
    report.set("view3d.written", o.view3d);
    report.set("view3d.format", view3d_format_name(out));
    report.set("view3d.surfaces", scene.objects.size() + scene.view3d.masks.size());
}

}  // namespace

RowView View3dCutoff::operator()(std::uint32_t i, RowView r) {
    if (max_ <= 0.0) return r;
    col_.clear();
    val_.clear();
    for (std::size_t k = 0; k < r.col.size(); ++k)
        if (!(glm::length(scene_.patches[r.col[k]].centroid - scene_.patches[i].centroid) > max_)) {
            col_.push_back(r.col[k]);
            val_.push_back(r.val[k]);
        }
    return RowView{col_, val_};
}

void write_view3d_output(const std::filesystem::path& path, const CsrMatrix& F, const Scene& scene, int out,
                         Report& report) {
    FFCUBE_CHECK(F.size() == scene.size() && F.rows_filled() == F.size());
    const std::size_t surfaces = scene.objects.size() + scene.view3d.masks.size();
    report.set("view3d.written", path.string());
    report.set("view3d.format", view3d_format_name(out));
    report.set("view3d.surfaces", surfaces);
    if (out != 2 || !scene.view3d.masks.empty() || scene.view3d.emit == 1) {
        write_view3d(path, view3d_table(F, scene), out);
        return;
    }
    // Object a's row: Σ over its patches i (increasing) and their entries (increasing column) of
    // A_i F_ij into the column of j's object, over Σ A_i: RowStreamChecks' sums, in its order.
    const std::size_t objects = scene.objects.size();
    std::vector<std::vector<std::uint32_t>> patches_of(objects);
    for (std::uint32_t i = 0; i < scene.size(); ++i) patches_of[scene.patches[i].object].push_back(i);
    std::vector<double> acc(objects, 0.0), val;
    std::vector<char> seen(objects, 0);
    std::vector<std::uint32_t> touched;
    View3dSparseWriter writer(path);
    for (std::size_t a = 0; a < objects; ++a) {
        double area = 0.0;
        touched.clear();
        for (const std::uint32_t i : patches_of[a]) {
            const Patch& p = scene.patches[i];
            area += p.area;
            const RowView r = F.row(i);
            for (std::size_t k = 0; k < r.col.size(); ++k) {
                const std::uint32_t b = scene.patches[r.col[k]].object;
                if (!seen[b]) seen[b] = 1, touched.push_back(b);
                acc[b] += p.area * static_cast<double>(r.val[k]);
            }
        }
        std::sort(touched.begin(), touched.end());
        val.clear();
        for (const std::uint32_t b : touched) {
            val.push_back(area > 0 ? acc[b] / area : acc[b]);
            acc[b] = 0.0, seen[b] = 0;
        }
        writer.append_row(touched, val);
    }
    writer.finish();
    report.set("view3d.entries", writer.entries());
}

std::unique_ptr<MatrixSink> open_elmer_sink(const SurfaceOutputOptions& o, std::uint32_t n) {
    if (o.elmer.empty()) return nullptr;
    return std::make_unique<ElmerViewFactorsWriter>(o.elmer, n, o.elmer_format == FileFormat::Binary);
}

void write_surface_outputs(const SurfaceOutputOptions& o, std::span<const double> row_sums,
                           const RowStreamChecks& checks, const Scene& scene, Report& report,
                           std::span<const double> obstructed, std::span<const float> row_error) {
    write_sky_outputs(o, row_sums, scene, report, obstructed, row_error);
    if (!o.view3d.empty()) write_view3d_file(o, checks.object_factors(), scene, report);
}

void write_sky_outputs(const SurfaceOutputOptions& o, std::span<const double> row_sums, const Scene& scene, Report& report,
                       std::span<const double> obstructed, std::span<const float> row_error) {
    write_sky_and_table(o, sky_view_factors(row_sums), scene, report, obstructed, row_error);
}

}  // namespace ffcube
