// The Python module `ffcube` (pybind11): load_scene, form_factors and solve, over the same
// composition root as the command line (src/pipeline): load_and_mesh, make_row_source,
// compute_form_factors, solve_and_report. Keyword arguments are the command line's options with
// dashes as underscores (src/python/kwargs.hpp); their words go through the pipeline's own parsers
// and validators, so a bad option raises the message the command line prints.
//
// The GIL is released while a scene is loaded and meshed, rows are computed and a solve runs: no
// Python object is touched there (arrays are made after, from the C++ results).
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <fmt/format.h>

#include <algorithm>
#include <cstdint>
#include <memory>
#include <optional>
#include <string>

#include "ffcube/core/error.hpp"
#include "ffcube/core/log.hpp"
#include "ffcube/core/timer.hpp"
#include "ffcube/formfactor/row_provider.hpp"
#include "ffcube/io/report.hpp"
#include "ffcube/pipeline/form_factors.hpp"
#include "ffcube/pipeline/row_source.hpp"
#include "ffcube/pipeline/scene_loading.hpp"
#include "ffcube/pipeline/solve.hpp"
#include "kwargs.hpp"
#include "module.hpp"

namespace py = pybind11;

namespace ffcube::python {
namespace {

// F as scipy.sparse.csr_matrix: the stored float32 values (bit for bit what .ffm files hold and
// what .mtx files print to 9 significant digits), int32 indices while they fit.
py::object to_csr(const CsrMatrix& F) {
    const std::size_t n = F.size(), nnz = F.nnz();
    py::array_t<float> data(static_cast<py::ssize_t>(nnz));
    std::copy(F.val().begin(), F.val().end(), data.mutable_data());
    py::object indices, indptr;
    if (nnz < (std::uint64_t{1} << 31) && n < (std::size_t{1} << 31)) {
        indices = vector_array<std::int32_t>(nnz, [&](std::size_t k) { return static_cast<std::int32_t>(F.col()[k]); });
        indptr = vector_array<std::int32_t>(n + 1, [&](std::size_t i) { return static_cast<std::int32_t>(F.row_ptr()[i]); });
    } else {
        indices = vector_array<std::int64_t>(nnz, [&](std::size_t k) { return static_cast<std::int64_t>(F.col()[k]); });
        indptr = vector_array<std::int64_t>(n + 1, [&](std::size_t i) { return static_cast<std::int64_t>(F.row_ptr()[i]); });
    }
    const py::object csr = py::module_::import("scipy.sparse").attr("csr_matrix");
    return csr(py::make_tuple(data, indices, indptr), py::arg("shape") = py::make_tuple(n, n));
}

py::object form_factors(const py::object& what, const py::kwargs& kwargs) {
    Kwargs kw(kwargs, "form_factors");
    RowOptions ro;
    kw.read_row_options(ro, /*enforce=*/true);
    const bool quiet = kw.flag("quiet", false);
    const bool want_report = kw.flag("report", false);
    const SceneArgument arg = scene_argument(what, kw, "form_factors");
    kw.finish();
    validate(ro);
    CsrMatrix F;
    std::string report_json;
    {
        py::gil_scoped_release nogil;
        LogScope log(quiet);
        Report report;
        report.set("command", "formfactors");
        const std::shared_ptr<const Scene> scene = scene_of(arg, report);
        RowSource rows = make_row_source(*scene, ro);
        for (const std::string& line : describe(rows)) info("{}", line);
        // The one path of `ffcube formfactors` (pipeline/form_factors.hpp), into memory.
        FormFactorFigures f;
        F = form_factor_matrix(*scene, rows, report, {}, &f);
        if (want_report) {  // the keys of `ffcube formfactors --report`, but for writing and checkpoints
            report.set("seconds", f.seconds);
            report_rates(report, rows, scene->size(), f.seconds);
            report_row_source(report, rows);
            report_matrix_stats(report, f.nnz, f.row_sums, f.reciprocity);
            report_json = report.dump();
        }
    }
    py::object csr = to_csr(F);
    if (!want_report) return csr;
    return py::make_tuple(csr, json_loads(report_json));
}

py::tuple solve(const py::object& what, const py::kwargs& kwargs) {
    Kwargs kw(kwargs, "solve");
    RowOptions ro;
    ro.far_field_emitters = kw.flag("far_field_emitters", true);  // as `ffcube solve` (--far-field-emitters)
    kw.read_row_options(ro, /*enforce=*/false);
    SolverOptions so;
    kw.read_solver_options(so);
    const bool allow_unconverged = kw.flag("allow_unconverged", false);
    const bool quiet = kw.flag("quiet", false);
    const SceneArgument arg = scene_argument(what, kw, "solve");
    kw.finish();
    validate(so);
    validate(ro);
    SolveResult res;
    std::string report_json;
    {
        py::gil_scoped_release nogil;
        LogScope log(quiet);
        Report report;
        report.set("command", "solve");
        const std::shared_ptr<const Scene> scene = scene_of(arg, report);
        RowSource rows = make_row_source(*scene, ro);
        for (const std::string& line : describe(rows)) info("{}", line);
        report.set("rows", rows.provider().name());
        res = solve_and_report(*scene, rows.provider(), so, report);
        report_row_source(report, rows);
        if (!res.converged()) {
            require_converged(res, so, allow_unconverged);  // NotConvergedError unless allowed
            warn("{}; returning the results anyway (allow_unconverged; the report says \"converged\": false)",
                 describe_unconverged(res, so));
        }
        report_json = report.dump();
    }
    const py::array_t<double> B = vec3_array(res.radiosity.size(), [&](std::size_t i) { return res.radiosity[i]; });
    return py::make_tuple(B, json_loads(report_json));
}

}  // namespace
}  // namespace ffcube::python

PYBIND11_MODULE(ffcube, m) {
    using namespace ffcube;
    using namespace ffcube::python;
    m.doc() = "ffcube: radiosity form factors (view factors) by hemicubes or rays, and radiosity solves. "
              "Keyword options are the command line's, dashes as underscores (README, 'in Python').";

    // The command line's exit codes become exceptions carrying its messages.
    py::register_exception<InputError>(m, "InputError", PyExc_ValueError);
    py::register_exception<IoError>(m, "IoError", PyExc_OSError);
    py::register_exception<GlError>(m, "GlError", PyExc_RuntimeError);
    py::register_exception<NotConvergedError>(m, "NotConvergedError", PyExc_RuntimeError);
    py::register_exception<InternalError>(m, "InternalError", PyExc_RuntimeError);

    py::class_<PyScene>(m, "Scene", "A meshed scene: its patches (rows and columns of F) and objects.")
        .def("__len__", [](const PyScene& s) { return s.scene->size(); })
        .def_property_readonly("areas",
                               [](const PyScene& s) {
                                   return vector_array<double>(s.scene->size(), [&](std::size_t i) { return s.scene->patches[i].area; });
                               },
                               "patch areas, scene units^2 (float64, n)")
        .def_property_readonly("patch_object",
                               [](const PyScene& s) {
                                   return vector_array<std::uint32_t>(s.scene->size(),
                                                                      [&](std::size_t i) { return s.scene->patches[i].object; });
                               },
                               "index into objects of each patch (uint32, n)")
        .def_property_readonly("objects", [](const PyScene& s) { return s.scene->objects; }, "object names")
        .def_property_readonly("centroids",
                               [](const PyScene& s) {
                                   return vec3_array(s.scene->size(), [&](std::size_t i) { return s.scene->patches[i].centroid + s.scene->origin; });
                               },
                               "patch centroids (float64, n x 3)")
        .def_property_readonly("normals",
                               [](const PyScene& s) {
                                   return vec3_array(s.scene->size(), [&](std::size_t i) { return s.scene->patches[i].normal; });
                               },
                               "unit front normals (float64, n x 3)")
        .def_property_readonly("source", [](const PyScene& s) { return s.scene->source; })
        .def_property_readonly("fingerprint", [](const PyScene& s) { return fmt::format("{:016x}", s.scene->fingerprint); })
        .def_property_readonly("report", [](const PyScene& s) { return json_loads(s.load_report); },
                               "loading and meshing figures, as in the command line's --report")
        .def_property_readonly("element_ids",
                               [](const PyScene& s) -> py::object {
                                   if (s.scene->patch_elements.size() != s.scene->size()) return py::none();
                                   return vector_array<std::uint64_t>(s.scene->size(),
                                                                      [&](std::size_t i) { return s.scene->patch_elements[i]; });
                               },
                               "the mesh element each patch comes from (uint64, n), for meshes read through Gmsh or meshio; "
                               "from a meshio.Mesh, 1 + the cell's index counted over mesh.cells in order; None otherwise")
        .def("cell_data", &cell_data_of, py::arg("values"),
             "cell_data(values) -> list of arrays, one per block of the meshio.Mesh this scene was loaded from, for "
             "mesh.cell_data[name]: values (one row per patch, shape (n,) or (n, k)) averaged over each cell's patches by "
             "area; NaN for a cell with no patch (lines, vertices, volume cells off the boundary)")
        .def("__repr__", [](const PyScene& s) {
            return fmt::format("<ffcube.Scene {}: {} patches, {} objects>", s.scene->source, s.scene->size(),
                               s.scene->objects.size());
        });

    m.def(
        "load_scene",
        [](const py::object& path, const py::kwargs& kwargs) {
            Kwargs kw(kwargs, "load_scene");
            if (is_meshio_mesh(path)) return load_meshio(path, kw);
            SceneOptions options;
            options.path = path_argument(path, "load_scene");
            kw.read_scene_options(options);
            const bool quiet = kw.flag("quiet", false);
            kw.finish();
            return load(options, quiet);
        },
        py::arg("path") = py::none(),
        "load_scene(path=None, **mesh_options) -> Scene. path: a scene file (OBJ, STL, .vs3, PLY, glTF, .msh ...), a "
        "meshio.Mesh (docs/fe-meshes.md), None: the built-in Cornell box. Options: max_patch_edge, patches, format, "
        "materials, no_subdivide, objects_by (a meshio.Mesh also 'field:NAME'), flip, quiet.");
    m.def("form_factors", &form_factors, py::arg("scene_or_path") = py::none(),
          "form_factors(scene_or_path=None, **options) -> scipy.sparse.csr_matrix (float32): F[i, j] = fraction of "
          "the energy leaving patch i that arrives at patch j; the rows `ffcube formfactors` writes for the same "
          "options. Options: method, resolution, backend, threads, rotate/no_rotate, seed, rays, correct, near_k, near_min_ff, "
          "far_field, enforce, quiet, and the mesh options when given a path. report=True: (F, report dict) with the "
          "keys of `ffcube formfactors --report`.");
    add_radiate(m);
    m.def("solve", &solve, py::arg("scene_or_path") = py::none(),
          "solve(scene_or_path=None, **options) -> (radiosity float64 n x 3, report dict), as `ffcube solve`. "
          "Options: those of form_factors (but enforce), and solver, tolerance, max_iterations, overshoot, "
          "row_cache_mb, allow_unconverged.");
}
