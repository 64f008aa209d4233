#include "kwargs.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <climits>
#include <cmath>
#include <cstdint>
#include <limits>

#include "ffcube/core/error.hpp"
#include "ffcube/scene/load_model.hpp"
#include "ffcube/scene/obj_loader.hpp"

namespace py = pybind11;

namespace ffcube::python {
namespace {

constexpr const char* kSceneKeywords[] = {"max_patch_edge", "patches", "format", "materials", "no_subdivide", "objects_by", "flip",
                                          "contact_cuts"};

// bool or numpy.bool_ (told by its type's name, so that no call imports numpy: an import can
// start threads, and a process with threads gets thread workers instead of forked ones).
bool is_bool(const py::handle& v) {
    if (PyBool_Check(v.ptr())) return true;
    const py::handle type = reinterpret_cast<PyObject*>(Py_TYPE(v.ptr()));
    return std::string(py::str(type.attr("__module__"))) == "numpy" && std::string(py::str(type.attr("__name__"))) == "bool_";
}
// int, or an integer type that says so with __index__ (numpy.int64 ...); not bool.
bool is_int(const py::handle& v) { return PyIndex_Check(v.ptr()) && !is_bool(v); }
// float, or any real number type (__float__: numpy.float32 ...); not bool, not complex.
bool is_real(const py::handle& v) {
    return is_int(v) || PyFloat_Check(v.ptr()) ||
           (!is_bool(v) && !PyComplex_Check(v.ptr()) && py::hasattr(v, "__float__") && !py::isinstance<py::str>(v));
}

std::string fspath(const py::object& value) { return py::str(py::module_::import("os").attr("fspath")(value)); }

bool is_pathlike(const py::object& value) {
    return py::isinstance<py::str>(value) || py::hasattr(value, "__fspath__");
}

}  // namespace

std::string cli_name(const std::string& keyword) {
    std::string s = "--" + keyword;
    for (char& c : s)
        if (c == '_') c = '-';
    return s;
}

std::string path_argument(const py::object& what, const char* function) {
    if (what.is_none()) return {};
    if (!is_pathlike(what))
        throw py::type_error(fmt::format("{}(): the scene must be a Scene, a path (str or os.PathLike) or None, not {}{}",
                                         function, std::string(py::str(what.get_type().attr("__name__"))),
                                         py::hasattr(what, "points") && py::hasattr(what, "cells")
                                             ? " (a meshio.Mesh: make it a Scene with load_scene(mesh) first)"
                                             : ""));
    std::string path = fspath(what);
    if (path.empty()) throw InputError(fmt::format("{}(): the scene path is empty (None means the built-in Cornell box)", function));
    return path;
}

Kwargs::Kwargs(const py::kwargs& kwargs, std::string function) : kwargs_(kwargs), function_(std::move(function)) {}

py::object Kwargs::take(const std::string& name) {
    accepted_.push_back(name);
    if (!kwargs_.contains(name.c_str())) return py::none();
    used_.insert(name);
    return kwargs_[name.c_str()];
}

std::string Kwargs::word(const std::string& name, const py::object& value) const {
    if (!py::isinstance<py::str>(value))
        throw py::type_error(fmt::format("{}(): {} must be a str, not {}", function_, name,
                                         std::string(py::str(value.get_type().attr("__name__")))));
    return value.cast<std::string>();
}

double Kwargs::number(const std::string& name, const py::object& value) const {
    if (!is_real(value))
        throw py::type_error(fmt::format("{}(): {} must be a number, not {}", function_, name,
                                         std::string(py::str(value.get_type().attr("__name__")))));
    return py::float_(value).cast<double>();
}

unsigned long long Kwargs::integer(const std::string& name, const py::object& value, long long lo,
                                   unsigned long long hi) const {
    if (!is_int(value))
        throw py::type_error(fmt::format("{}(): {} must be an int, not {}", function_, name,
                                         std::string(py::str(value.get_type().attr("__name__")))));
    const py::object index = py::reinterpret_steal<py::object>(PyNumber_Index(value.ptr()));
    if (!index) throw py::error_already_set();
    int overflow = 0;
    const long long v = PyLong_AsLongLongAndOverflow(index.ptr(), &overflow);
    const std::string text = py::str(index);
    if (overflow < 0 || (overflow == 0 && v < lo))
        throw InputError(fmt::format("{} {}: must be at least {}", cli_name(name), text, lo));
    if (overflow == 0) {
        if (static_cast<unsigned long long>(v) > hi) throw InputError(fmt::format("{} {}: must be at most {}", cli_name(name), text, hi));
        return static_cast<unsigned long long>(v);
    }
    const unsigned long long u = PyLong_AsUnsignedLongLong(index.ptr());
    if (PyErr_Occurred()) {
        PyErr_Clear();
        throw InputError(fmt::format("{} {}: must be at most {}", cli_name(name), text, hi));
    }
    if (u > hi) throw InputError(fmt::format("{} {}: must be at most {}", cli_name(name), text, hi));
    return u;
}

bool Kwargs::boolean(const std::string& name, const py::object& value) const {
    if (!is_bool(value))
        throw py::type_error(fmt::format("{}(): {} must be True or False, not {}", function_, name,
                                         std::string(py::str(value.get_type().attr("__name__")))));
    return PyObject_IsTrue(value.ptr()) == 1;
}

bool Kwargs::flag(const std::string& name, bool fallback) {
    const py::object v = take(name);
    return v.is_none() ? fallback : boolean(name, v);
}

void Kwargs::read_scene_options(SceneOptions& o, std::string* field) {
    if (py::object v = take("max_patch_edge"); !v.is_none()) {
        o.max_patch_edge = number("max_patch_edge", v);
        // The command line refuses 0 (CLI::PositiveNumber); 0 here would silently mean the default.
        if (!(o.max_patch_edge > 0) || !std::isfinite(o.max_patch_edge))
            throw InputError(fmt::format("--max-patch-edge {}: must be a finite length > 0", o.max_patch_edge));
    }
    if (py::object v = take("patches"); !v.is_none())
        o.patches = static_cast<std::size_t>(integer("patches", v, 1, std::numeric_limits<std::uint32_t>::max()));
    if (py::object v = take("format"); !v.is_none()) o.format = parse_scene_format(word("format", v));
    if (py::object v = take("materials"); !v.is_none()) {
        if (!is_pathlike(v)) throw py::type_error(fmt::format("{}(): materials must be a path (str or os.PathLike)", function_));
        o.materials = fspath(v);
    }
    if (py::object v = take("no_subdivide"); !v.is_none()) o.subdivide = !boolean("no_subdivide", v);
    if (py::object v = take("objects_by"); !v.is_none()) {
        const std::string w = word("objects_by", v);
        if (w == "group" || w == "entity" || w == "element")  // a mesh read through Gmsh, as --objects-by
            o.fe_objects_by = w == "group" ? FeObjectsBy::group : w == "entity" ? FeObjectsBy::entity : FeObjectsBy::element;
        else if (w.starts_with("field:") && field && w.size() > 6)
            *field = w.substr(6);
        else if (w.starts_with("field:") && w.size() > 6)  // a file: a legacy .vtk's cell array, as --objects-by
            o.fe_field = w.substr(6);
        else if (w.starts_with("field:"))
            throw InputError(fmt::format("objects_by='{}': field:NAME names an integer cell-data array (of a meshio.Mesh or a "
                                         "legacy .vtk file)",
                                         w));
        else
            o.objects_by = parse_objects_by(w);
    }
    if (py::object v = take("flip"); !v.is_none()) {
        // A list of names, or one string of names separated by commas (as --flip a,b).
        if (py::isinstance<py::str>(v)) {
            const std::string all = v.cast<std::string>();
            for (std::size_t at = 0; at <= all.size();) {
                const std::size_t comma = std::min(all.find(',', at), all.size());
                if (comma > at) o.flip.push_back(all.substr(at, comma - at));
                at = comma + 1;
            }
        } else if (py::isinstance<py::list>(v) || py::isinstance<py::tuple>(v)) {
            for (const py::handle item : v) o.flip.push_back(word("flip", py::reinterpret_borrow<py::object>(item)));
        } else {
            throw py::type_error(fmt::format("{}(): flip must be a str or a list of str, not {}", function_,
                                             std::string(py::str(v.get_type().attr("__name__")))));
        }
    }
    if (py::object v = take("contact_cuts"); !v.is_none()) o.contact_cuts = parse_contact_cuts(word("contact_cuts", v));
    validate(o);
}

std::string Kwargs::scene_option_given() const {
    for (const char* k : kSceneKeywords)
        if (kwargs_.contains(k)) return k;
    return {};
}

void Kwargs::read_row_options(RowOptions& o, bool enforce) {
    o.method_auto = true;  // method="auto", the command line's default, unless named
    // The rows' accuracy target: tolerance= where the function makes a matrix (form_factors), as
    // --tolerance; row_tolerance= where tolerance= is the solver's (solve), as --row-tolerance.
    o.tolerance = kDefaultTolerance;
    if (py::object v = take(enforce ? "tolerance" : "row_tolerance"); !v.is_none()) {
        o.tolerance = number(enforce ? "tolerance" : "row_tolerance", v);
        o.tolerance_given = true;
    }
    if (py::object v = take("method"); !v.is_none()) set_row_method(word("method", v), o);
    if (py::object v = take("resolution"); !v.is_none())
        o.resolution = static_cast<int>(integer("resolution", v, INT_MIN, INT_MAX));  // check_row_resolution says the rule
    if (py::object v = take("backend"); !v.is_none()) o.backend = parse_backend(word("backend", v));
    if (py::object v = take("threads"); !v.is_none())
        o.threads = static_cast<unsigned>(integer("threads", v, 0, std::numeric_limits<unsigned>::max()));
    const py::object rotate = take("rotate"), no_rotate = take("no_rotate");
    if (!rotate.is_none()) o.rotate = boolean("rotate", rotate);
    if (!no_rotate.is_none()) {
        const bool off = boolean("no_rotate", no_rotate);
        if (!rotate.is_none() && off == o.rotate)
            throw InputError(fmt::format("{}(): rotate={} and no_rotate={} contradict each other", function_,
                                         o.rotate ? "True" : "False", off ? "True" : "False"));
        o.rotate = !off;
    }
    if (py::object v = take("seed"); !v.is_none())
        o.seed = integer("seed", v, 0, std::numeric_limits<std::uint64_t>::max());
    if (py::object v = take("rays"); !v.is_none()) {
        o.rays = integer("rays", v, 0, std::numeric_limits<std::uint64_t>::max());
        o.rays_given = true;
    }
    if (py::object v = take("correct"); !v.is_none()) o.correct = parse_correction(word("correct", v));
    if (py::object v = take("near_k"); !v.is_none()) o.near_k = number("near_k", v);
    if (py::object v = take("near_min_ff"); !v.is_none()) o.near_min_ff = number("near_min_ff", v);
    if (py::object v = take("exact_visibility"); !v.is_none()) {  // its range: validate(RowOptions)
        if (py::isinstance<py::str>(v)) {
            parse_exact_visibility(word("exact_visibility", v), o);  // "auto" | "off" | a number, as the CLI
        } else {
            o.exact_visibility_occluders = integer("exact_visibility", v, 0, std::numeric_limits<std::size_t>::max());
            o.exact_visibility_auto = false;
        }
    }
    if (py::object v = take("far_field"); !v.is_none()) o.far_field = parse_far_field(word("far_field", v));
    // A file `ffcube calibrate` wrote (pipeline/cost_model.hpp), as --cost-model.
    if (py::object v = take("cost_model"); !v.is_none()) o.cost_model = read_cost_model(word("cost_model", v));
    if (enforce)
        if (py::object v = take("enforce"); !v.is_none()) o.enforce = parse_enforce_request(word("enforce", v));
}

void Kwargs::read_solver_options(SolverOptions& o) {
    if (py::object v = take("solver"); !v.is_none()) o.method = parse_solver_method(word("solver", v));
    if (py::object v = take("tolerance"); !v.is_none()) o.tolerance = number("tolerance", v);
    if (py::object v = take("max_iterations"); !v.is_none())
        o.max_iterations = integer("max_iterations", v, 0, std::numeric_limits<std::uint64_t>::max());
    if (py::object v = take("overshoot"); !v.is_none()) {
        // True is the command line's --overshoot alone: the default factor; False: none (1).
        if (is_bool(v))
            o.overshoot = PyObject_IsTrue(v.ptr()) == 1 ? kDefaultOvershoot : 1.0;
        else
            o.overshoot = number("overshoot", v);
    }
    if (py::object v = take("row_cache_mb"); !v.is_none()) o.row_cache_mb = number("row_cache_mb", v);
}

std::optional<double> Kwargs::optional_number(const std::string& name) {
    const py::object v = take(name);
    if (v.is_none()) return std::nullopt;
    return number(name, v);
}

std::string Kwargs::optional_path(const std::string& name) {
    const py::object v = take(name);
    if (v.is_none()) return {};
    if (!is_pathlike(v))
        throw py::type_error(fmt::format("{}(): {} must be a path (str or os.PathLike), not {}", function_, name,
                                         std::string(py::str(v.get_type().attr("__name__")))));
    return fspath(v);
}

void Kwargs::finish() const {
    for (const auto& item : kwargs_) {
        const std::string name = py::str(item.first);
        if (used_.count(name)) continue;
        std::string list;
        for (const std::string& a : accepted_) list += (list.empty() ? "" : ", ") + a;
        throw py::type_error(fmt::format("{}() got an unexpected keyword argument '{}' (it takes: {})", function_, name, list));
    }
}

}  // namespace ffcube::python
