// Shared by the Python module's sources (module.cpp, radiate.cpp): the Scene object, the scene
// argument of the computations, logging scope and array helpers.
#pragma once

#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>

#include <fmt/format.h>

#include <memory>
#include <string>
#include <vector>

#include "ffcube/core/log.hpp"
#include "ffcube/io/report.hpp"
#include "ffcube/pipeline/scene_loading.hpp"
#include "kwargs.hpp"

namespace ffcube::python {

namespace py = pybind11;

// A meshed scene, shared by the Python object and any computation running on it.
struct PyScene {
    std::shared_ptr<const Scene> scene;
    std::string load_report;  // the JSON of load_and_mesh's figures (scene, patches, meshing.*, time.*)
    // Loaded from a meshio.Mesh: the number of cells of each of its blocks (Scene.cell_data maps
    // patches back to them); empty otherwise.
    std::vector<std::size_t> mesh_blocks;
};

// set_log_level for the duration of one call (quiet=True: warnings and errors only).
class LogScope {
public:
    explicit LogScope(bool quiet) : saved_(log_level()) {
        if (quiet) set_log_level(LogLevel::Quiet);
    }
    ~LogScope() { set_log_level(saved_); }
    LogScope(const LogScope&) = delete;
    LogScope& operator=(const LogScope&) = delete;

private:
    LogLevel saved_;
};

inline py::object json_loads(const std::string& text) { return py::module_::import("json").attr("loads")(text); }

inline PyScene load(const SceneOptions& options, bool quiet) {
    PyScene s;
    py::gil_scoped_release nogil;
    LogScope log(quiet);
    Report report;
    s.scene = std::make_shared<const Scene>(load_and_mesh(options, report));
    s.load_report = report.dump();
    return s;
}

// The scene a computation runs on: a Scene object as it is (mesh options then refused), or a
// path (str, os.PathLike) or None (the built-in Cornell box) to load with the mesh options.
struct SceneArgument {
    std::shared_ptr<const Scene> scene;
    SceneOptions options;
};

inline SceneArgument scene_argument(const py::object& what, Kwargs& kw, const char* function) {
    if (py::isinstance<PyScene>(what)) {
        const std::string given = kw.scene_option_given();
        if (!given.empty())
            throw py::type_error(fmt::format("{}(): '{}' is a mesh option; pass it to load_scene() instead of a Scene",
                                             function, given));
        return {what.cast<const PyScene&>().scene, {}};
    }
    SceneArgument a;
    a.options.path = path_argument(what, function);
    kw.read_scene_options(a.options);
    return a;
}

// The scene, loaded and meshed into the report as the command line does unless it was given
// loaded (then only its name, size and fingerprint are recorded). Call with the GIL released.
inline std::shared_ptr<const Scene> scene_of(const SceneArgument& a, Report& report) {
    if (!a.scene) return std::make_shared<const Scene>(load_and_mesh(a.options, report));
    report.set("scene", a.scene->source);
    report.set("patches", a.scene->size());
    report.set("objects", a.scene->objects.size());
    report.set("fingerprint", fmt::format("{:016x}", a.scene->fingerprint));
    return a.scene;
}

template <typename T>
py::array_t<T> vector_array(std::size_t n, auto&& value) {
    py::array_t<T> a(static_cast<py::ssize_t>(n));
    auto m = a.template mutable_unchecked<1>();
    for (std::size_t i = 0; i < n; ++i) m(static_cast<py::ssize_t>(i)) = value(i);
    return a;
}

inline py::array_t<double> vec3_array(std::size_t n, auto&& value) {
    py::array_t<double> a({static_cast<py::ssize_t>(n), py::ssize_t{3}});
    auto m = a.mutable_unchecked<2>();
    for (std::size_t i = 0; i < n; ++i) {
        const Vec3 v = value(i);
        const auto r = static_cast<py::ssize_t>(i);
        m(r, 0) = v.x;
        m(r, 1) = v.y;
        m(r, 2) = v.z;
    }
    return a;
}

// meshio (meshio.cpp): whether `what` is a meshio.Mesh (points and cells); load_scene of one;
// Scene.cell_data: per-patch values as a list of per-cell arrays, one per block of the mesh.
bool is_meshio_mesh(const py::object& what);
PyScene load_meshio(const py::object& mesh, Kwargs& kw);
py::list cell_data_of(const PyScene& s, const py::object& values);

// Registers radiate() and the Radiation class (radiate.cpp).
void add_radiate(py::module_& m);

}  // namespace ffcube::python
