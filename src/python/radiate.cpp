// ffcube.radiate() and ffcube.Radiation (README "heat transfer", docs/radiate.md "Python"): the
// gray-body and banded exchange of `ffcube radiate` (solver/radiate.hpp) from Python. radiate()
// takes the command line's inputs; Radiation keeps F, the areas and the emissivities, and solves
// new temperatures many times (a transient model's steps) without rebuilding anything.
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <fmt/format.h>

#include <cmath>
#include <limits>
#include <map>
#include <optional>

#include "ffcube/core/error.hpp"
#include "ffcube/core/input_file.hpp"
#include "ffcube/core/timer.hpp"
#include "ffcube/io/csv.hpp"
#include "ffcube/io/ffm.hpp"
#include "ffcube/pipeline/form_factors.hpp"
#include "ffcube/pipeline/row_source.hpp"
#include "ffcube/solver/radiate.hpp"
#include "module.hpp"

namespace ffcube::python {
namespace {

std::string type_name(const py::handle& v) { return py::str(v.get_type().attr("__name__")); }

// surfaces=: a path to S.csv, or a dict {object: {"emissivity": e, "temperature": T}} (or
// "heat_flux": q instead of "temperature"). The dict goes through the CSV's parser as lines of
// "surfaces", so that its refusals are the command line's.
std::vector<NamedSurface> surfaces_argument(const py::object& v, std::string& source) {
    if (v.is_none()) throw py::type_error("radiate(): surfaces= is required (a path to S.csv, or a dict)");
    if (py::isinstance<py::dict>(v)) {
        source = "surfaces";
        std::string text = "object,emissivity,temperature,heat_flux\n";
        for (const auto& [key, value] : v.cast<py::dict>()) {
            if (!py::isinstance<py::str>(key) || !py::isinstance<py::dict>(value))
                throw py::type_error("radiate(): surfaces= maps object names (str) to dicts {'emissivity': e, "
                                     "'temperature': T} or {'emissivity': e, 'heat_flux': q}");
            const py::dict d = value.cast<py::dict>();
            const auto field = [&](const char* name) -> std::string {
                if (!d.contains(name) || d[name].is_none()) return "";
                return fmt::format("{:.17g}", d[name].cast<double>());
            };
            for (const auto& [k, unused] : d) {
                const std::string name = py::str(k);
                if (name != "emissivity" && name != "temperature" && name != "heat_flux")
                    throw py::type_error(fmt::format("radiate(): surfaces['{}'] has '{}'; its keys are emissivity, "
                                                     "temperature, heat_flux",
                                                     key.cast<std::string>(), name));
            }
            text += csv_field(key.cast<std::string>()) + "," + field("emissivity") + "," + field("temperature") + "," +
                    field("heat_flux") + "\n";
        }
        return parse_surfaces_csv(text, source);
    }
    source = path_argument(v, "radiate");
    return parse_surfaces_csv(read_input_file(source, "a CSV file", "the surfaces"), source);
}

// A scipy.sparse matrix (anything with tocsr()) as a CsrMatrix of n × n, float32 values.
CsrMatrix csr_argument(const py::object& m, std::size_t n, const char* function) {
    if (!py::hasattr(m, "tocsr"))
        throw py::type_error(fmt::format("{}(): F must be a scipy.sparse matrix or a path to a .ffm file, not {}", function,
                                         type_name(m)));
    py::object csr = m.attr("tocsr")();
    if (!csr.attr("has_canonical_format").cast<bool>()) {  // sorted columns, no duplicates: on a copy
        csr = csr.attr("copy")();
        csr.attr("sum_duplicates")();
    }
    const py::tuple shape = csr.attr("shape");
    if (shape[0].cast<std::size_t>() != n || shape[1].cast<std::size_t>() != n)
        throw InputError(fmt::format("{}(): F is {} x {} but the scene has {} patches", function,
                                     shape[0].cast<std::size_t>(), shape[1].cast<std::size_t>(), n));
    const auto ptr = py::array_t<std::int64_t, py::array::c_style | py::array::forcecast>(csr.attr("indptr"));
    const auto col = py::array_t<std::int64_t, py::array::c_style | py::array::forcecast>(csr.attr("indices"));
    const auto val = py::array_t<float, py::array::c_style | py::array::forcecast>(csr.attr("data"));
    const auto p = ptr.unchecked<1>();
    const auto cl = col.unchecked<1>();
    const auto vl = val.unchecked<1>();
    if (static_cast<std::size_t>(p.shape(0)) != n + 1 || cl.shape(0) != vl.shape(0) || p(0) != 0 ||
        p(static_cast<py::ssize_t>(n)) != vl.shape(0))
        throw InputError(fmt::format("{}(): F's indptr, indices and data do not fit together", function));
    CsrMatrix F(static_cast<std::uint32_t>(n));
    std::vector<std::uint32_t> c;
    std::vector<float> v;
    for (std::size_t i = 0; i < n; ++i) {
        c.clear();
        v.clear();
        const auto r0 = p(static_cast<py::ssize_t>(i)), r1 = p(static_cast<py::ssize_t>(i + 1));
        if (r1 < r0) throw InputError(fmt::format("{}(): F's indptr decreases at row {}", function, i));
        for (std::int64_t k = r0; k < r1; ++k) {
            const float x = vl(k);
            const std::int64_t j = cl(k);
            if (j < 0 || static_cast<std::size_t>(j) >= n)
                throw InputError(fmt::format("{}(): F[{}, {}]: column out of range", function, i, j));
            if (!std::isfinite(x) || x < 0.0f)
                throw InputError(fmt::format("{}(): F[{}, {}] = {} must be finite and >= 0", function, i, j, x));
            if (x == 0.0f) continue;
            c.push_back(static_cast<std::uint32_t>(j));
            v.push_back(x);
        }
        // append_row wants ascending columns: sort this row's pairs (csr_matrix may be unsorted).
        std::vector<std::size_t> order(c.size());
        for (std::size_t k = 0; k < order.size(); ++k) order[k] = k;
        std::sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) { return c[a] < c[b]; });
        std::vector<std::uint32_t> cs(c.size());
        std::vector<float> vs(c.size());
        for (std::size_t k = 0; k < order.size(); ++k) {
            cs[k] = c[order[k]];
            vs[k] = v[order[k]];
        }
        F.append_row(cs, vs);
    }
    return F;
}

// A per-patch value from a number (every patch), a dict {object: value} (NaN for the objects it
// does not name) or a sequence of n numbers.
std::vector<double> per_patch(const py::object& v, const Scene& scene, const char* what) {
    const std::size_t n = scene.size();
    std::vector<double> out(n, std::numeric_limits<double>::quiet_NaN());
    if (v.is_none()) return out;
    if (py::isinstance<py::dict>(v)) {
        std::map<std::string, std::uint32_t> index;
        for (std::uint32_t k = 0; k < scene.objects.size(); ++k) index.emplace(scene.objects[k], k);
        std::vector<double> by_object(scene.objects.size(), std::numeric_limits<double>::quiet_NaN());
        for (const auto& [key, value] : v.cast<py::dict>()) {
            const std::string name = py::str(key);
            const auto it = index.find(name);
            if (it == index.end()) throw InputError(fmt::format("{}: the scene has no object '{}'", what, name));
            by_object[it->second] = value.cast<double>();
        }
        for (std::size_t i = 0; i < n; ++i) out[i] = by_object[scene.patches[i].object];
        return out;
    }
    if (py::isinstance<py::float_>(v) || py::isinstance<py::int_>(v)) {
        std::fill(out.begin(), out.end(), v.cast<double>());
        return out;
    }
    const auto a = py::array_t<double, py::array::c_style | py::array::forcecast>(v);
    if (a.ndim() != 1 || static_cast<std::size_t>(a.shape(0)) != n)
        throw InputError(fmt::format("{}: {} values for {} patches", what, a.size(), n));
    for (std::size_t i = 0; i < n; ++i) out[i] = a.at(i);
    return out;
}

py::dict result_dict(const Scene& scene, const RadiateResult& r) {
    const std::size_t n = scene.size();
    py::dict d;
    d["temperature"] = vector_array<double>(n, [&](std::size_t i) { return r.temperature[i]; });
    d["heat_flux"] = vector_array<double>(n, [&](std::size_t i) { return r.heat_flux[i]; });
    d["radiosity"] = vector_array<double>(n, [&](std::size_t i) { return r.radiosity[i]; });
    d["irradiation"] = vector_array<double>(n, [&](std::size_t i) { return r.irradiation[i]; });
    // Per object: power Σ A q (W), heat flux power / area, temperature (Σ A T⁴ / Σ A)^¼.
    const std::size_t m = scene.objects.size();
    std::vector<double> area(m, 0.0), power(m, 0.0), t4(m, 0.0);
    for (std::size_t i = 0; i < n; ++i) {
        const Patch& p = scene.patches[i];
        area[p.object] += p.area;
        power[p.object] += p.area * r.heat_flux[i];
        t4[p.object] += p.area * std::pow(r.temperature[i], 4);
    }
    d["objects"] = scene.objects;
    d["object_power"] = vector_array<double>(m, [&](std::size_t k) { return power[k]; });
    d["object_heat_flux"] = vector_array<double>(m, [&](std::size_t k) { return area[k] > 0.0 ? power[k] / area[k] : 0.0; });
    d["object_temperature"] =
        vector_array<double>(m, [&](std::size_t k) { return area[k] > 0.0 ? std::pow(t4[k] / area[k], 0.25) : 0.0; });
    d["power"] = r.power;
    d["sky"] = r.sky;
    d["balance_error"] = r.balance_error;
    d["iterations"] = r.iterations;
    d["residual"] = r.residual;
    return d;
}

py::tuple radiate(const py::object& what, const py::kwargs& kwargs) {
    Kwargs kw(kwargs, "radiate");
    RowOptions ro;
    kw.read_row_options(ro, /*enforce=*/false);
    RadiateOptions opt;
    opt.sky_temperature = kw.optional_number("sky_temperature");
    opt.threads = ro.threads;
    const std::string matrix = kw.optional_path("matrix");
    const std::string bands_path = kw.optional_path("bands");
    const py::object surfaces = kw.value("surfaces");
    const py::object fallback_arg = kw.value("default_surface");
    const bool quiet = kw.flag("quiet", false);
    const SceneArgument arg = scene_argument(what, kw, "radiate");
    kw.finish();
    validate(ro);
    validate(opt);
    std::string source;
    const std::vector<NamedSurface> lines = surfaces_argument(surfaces, source);
    std::optional<SurfaceSpec> fallback;
    if (!fallback_arg.is_none()) {
        if (py::isinstance<py::str>(fallback_arg))
            fallback = parse_default_surface(fallback_arg.cast<std::string>());
        else {
            const auto pair = fallback_arg.cast<std::pair<double, double>>();
            fallback = parse_default_surface(fmt::format("{:.17g},{:.17g}", pair.first, pair.second));
        }
    }
    std::vector<NamedBand> band_lines;
    if (!bands_path.empty()) band_lines = parse_bands_csv(read_input_file(bands_path, "a CSV file", "the bands"), bands_path);
    RadiateResult r;
    std::shared_ptr<const Scene> scene;
    std::string report_json;
    {
        py::gil_scoped_release nogil;
        LogScope log(quiet);
        Report report;
        report.set("command", "radiate");
        Stopwatch total;
        scene = scene_of(arg, report);
        if (scene->drawn) throw InputError(fmt::format("{}: has obstruction-only surfaces; radiate needs every surface "
                                                       "to take part in the exchange",
                                                       scene->source));
        const std::vector<SurfaceSpec> object_spec = surfaces_for_objects(scene->objects, lines, source, fallback);
        Stopwatch watch;
        CsrMatrix F;
        if (!matrix.empty()) {
            FfmFile ffm = read_ffm(matrix);
            check_ffm_matches(ffm, *scene);
            F = std::move(ffm.matrix);
            report.set("rows", "matrix");
        } else {
            RowSource rows = make_row_source(*scene, resolve_row_method(ro, scene->drawn_scene()));
            report.set("rows", rows.provider().name());
            FormFactorOptions fo;  // the one path (pipeline/form_factors.hpp); no reciprocity check to report
            fo.reciprocity = false;
            F = form_factor_matrix(*scene, rows, report, fo);
        }
        report.set("time.rows", watch.seconds());
        std::vector<double> area(scene->size());
        std::vector<std::uint32_t> object(scene->size());
        std::vector<SurfaceSpec> spec(scene->size());
        for (std::size_t i = 0; i < scene->size(); ++i) {
            area[i] = scene->patches[i].area;
            object[i] = scene->patches[i].object;
            spec[i] = object_spec[object[i]];
        }
        opt.patch_name = [s = scene](std::uint32_t i) {
            return fmt::format("patch {} of object '{}'", i, s->objects[s->patches[i].object]);
        };
        watch.restart();
        if (!band_lines.empty()) {
            std::vector<double> gray(object_spec.size());
            for (std::size_t k = 0; k < gray.size(); ++k) gray[k] = object_spec[k].emissivity;
            r = solve_radiation_bands(F, area, spec, object, bands_for_objects(scene->objects, band_lines, bands_path, gray), opt);
        } else {
            r = solve_radiation(F, area, spec, opt);
        }
        report.set("time.solve", watch.seconds());
        report.set("converged", true);
        report.set("solver.iterations", r.iterations);
        report.set("solver.residual", r.residual);
        report.set("solver.min_emissivity", r.min_emissivity);
        report.set("solver.bands", r.bands);
        report.set("solver.outer_iterations", r.outer_iterations);
        report.set("energy.power", r.power);
        report.set("energy.sky", r.sky);
        report.set("energy.absolute_power", r.absolute_power);
        report.set("energy.relative_error", r.balance_error);
        report.set("time.total", total.seconds());
        report_json = report.dump();
    }
    return py::make_tuple(result_dict(*scene, r), json_loads(report_json));
}

// A reusable exchange: F, areas and emissivities kept; solve() takes new temperatures and fluxes.
struct PyRadiation {
    std::shared_ptr<const Scene> scene;
    CsrMatrix F;
    std::vector<double> area, emissivity;
    std::vector<std::uint32_t> object;
    std::optional<double> sky;
};

PyRadiation make_radiation(const py::object& f, const PyScene& s, const py::object& emissivity,
                           const py::object& sky_temperature) {
    PyRadiation r;
    r.scene = s.scene;
    const Scene& scene = *r.scene;
    if (py::isinstance<py::str>(f) || py::hasattr(f, "__fspath__")) {
        const std::string path = py::str(py::module_::import("os").attr("fspath")(f));
        py::gil_scoped_release nogil;
        FfmFile ffm = read_ffm(path);
        check_ffm_matches(ffm, scene);
        r.F = std::move(ffm.matrix);
    } else {
        r.F = csr_argument(f, scene.size(), "Radiation");
    }
    r.emissivity = per_patch(emissivity, scene, "Radiation emissivity");
    r.area.resize(scene.size());
    r.object.resize(scene.size());
    for (std::size_t i = 0; i < scene.size(); ++i) {
        r.area[i] = scene.patches[i].area;
        r.object[i] = scene.patches[i].object;
        if (!(r.emissivity[i] > 0.0 && r.emissivity[i] <= 1.0))
            throw InputError(fmt::format("Radiation: patch {} of object '{}': emissivity {} must be in (0, 1]{}", i,
                                         scene.objects[r.object[i]], r.emissivity[i],
                                         std::isnan(r.emissivity[i]) ? " (its object is not in the dict)" : ""));
    }
    if (!sky_temperature.is_none()) r.sky = sky_temperature.cast<double>();
    return r;
}

py::dict radiation_solve(const PyRadiation& self, const py::object& temperature, const py::object& heat_flux,
                         const py::object& sky_temperature, double tolerance) {
    const Scene& scene = *self.scene;
    const std::vector<double> t = per_patch(temperature, scene, "temperature");
    const std::vector<double> q = per_patch(heat_flux, scene, "heat_flux");
    std::vector<SurfaceSpec> spec(scene.size());
    for (std::size_t i = 0; i < scene.size(); ++i) {
        const bool has_t = !std::isnan(t[i]), has_q = !std::isnan(q[i]);
        if (has_t == has_q)
            throw InputError(fmt::format("patch {} of object '{}' has {}: give exactly one of temperature and heat_flux",
                                         i, scene.objects[self.object[i]], has_t ? "both a temperature and a heat flux"
                                                                                 : "neither a temperature nor a heat flux"));
        spec[i] = {self.emissivity[i], has_t ? SurfaceCondition::Temperature : SurfaceCondition::HeatFlux,
                   has_t ? t[i] : q[i]};
    }
    RadiateOptions opt;
    opt.tolerance = tolerance;
    validate(opt);
    opt.sky_temperature = sky_temperature.is_none() ? self.sky : std::optional<double>(sky_temperature.cast<double>());
    opt.patch_name = [&scene, &self](std::uint32_t i) {
        return fmt::format("patch {} of object '{}'", i, scene.objects[self.object[i]]);
    };
    RadiateResult r;
    {
        py::gil_scoped_release nogil;
        r = solve_radiation(self.F, self.area, spec, opt);
    }
    py::dict d = result_dict(scene, r);
    d["seconds"] = r.seconds;
    return d;
}

}  // namespace

void add_radiate(py::module_& m) {
    m.def("radiate", &radiate, py::arg("scene_or_path") = py::none(),
          "radiate(scene_or_path=None, surfaces=..., sky_temperature=None, matrix=None, bands=None, "
          "default_surface=None, **options) -> (dict, report dict), as `ffcube radiate`. surfaces: a path to "
          "S.csv or a dict {object: {'emissivity': e, 'temperature': T}} ('heat_flux': q instead of 'temperature'). "
          "The dict holds per-patch float64 arrays temperature, heat_flux, radiosity, irradiation (K, W/m^2), per-object "
          "object_power (W), object_heat_flux, object_temperature, and power, sky, balance_error, iterations, residual. "
          "Options: those of form_factors (method, resolution, ...) and the mesh options when given a path.");
    py::class_<PyRadiation>(m, "Radiation",
                            "Radiation(F, scene, emissivity, sky_temperature=None): gray-body exchange on F kept in memory; "
                            "solve() many times with new temperatures (docs/radiate.md, Python).")
        .def(py::init(&make_radiation), py::arg("F"), py::arg("scene"), py::arg("emissivity"),
             py::arg("sky_temperature") = py::none(),
             "F: scipy.sparse matrix (form_factors()) or a .ffm path; scene: the Scene F was computed on; emissivity: "
             "a number, a dict {object: e} or n values.")
        .def("solve", &radiation_solve, py::arg("temperature") = py::none(), py::arg("heat_flux") = py::none(),
             py::arg("sky_temperature") = py::none(), py::arg("tolerance") = 1e-10,
             "solve(temperature=None, heat_flux=None, sky_temperature=None, tolerance=1e-10) -> dict (as radiate()'s; "
             "tolerance: GMRES's relative residual, as `ffcube radiate --set tolerance=`). Each of "
             "temperature (K) and heat_flux (W/m^2, net leaving) is a number, a dict {object: value} or n values with "
             "NaN where not given; every patch needs exactly one.")
        .def(
            "conductances",
            [](const PyRadiation& self) {
                ConductanceResult g;
                {
                    py::gil_scoped_release nogil;
                    g = radiative_conductances(self.F, self.area, self.emissivity, self.object,
                                               static_cast<std::uint32_t>(self.scene->objects.size()), RadiateOptions{});
                }
                const std::size_t k = g.gr.size();
                py::array_t<double> gr({static_cast<py::ssize_t>(k), static_cast<py::ssize_t>(k)});
                auto a = gr.mutable_unchecked<2>();
                for (std::size_t i = 0; i < k; ++i)
                    for (std::size_t j = 0; j < k; ++j) a(static_cast<py::ssize_t>(i), static_cast<py::ssize_t>(j)) = g.gr[i][j];
                return py::make_tuple(gr, vector_array<double>(k, [&](std::size_t i) { return g.gr_sky[i]; }));
            },
            "conductances() -> (GR objects x objects, GR to the sky), m^2: GR[k, l] = eps_k A_k B_kl (Gebhart).")
        .def_property_readonly("objects", [](const PyRadiation& self) { return self.scene->objects; });
}

}  // namespace ffcube::python
