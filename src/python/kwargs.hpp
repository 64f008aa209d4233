// Keyword arguments of the Python module into the pipeline's option structs. The names are the
// command line's options with dashes as underscores (max_patch_edge for --max-patch-edge); words
// go through the pipeline's parsers (pipeline/options.hpp, solver/solver.hpp), so a bad value
// raises the command line's message (ffcube.InputError, a ValueError). A keyword the function does
// not take raises TypeError naming it and listing the ones it takes; a value of the wrong Python
// type raises TypeError naming the keyword.
#pragma once

#include <pybind11/pybind11.h>

#include <optional>
#include <set>
#include <string>
#include <vector>

#include "ffcube/pipeline/options.hpp"
#include "ffcube/solver/solver.hpp"

namespace ffcube::python {

class Kwargs {
public:
    Kwargs(const pybind11::kwargs& kwargs, std::string function);

    // path's siblings: max_patch_edge, patches, format, materials, no_subdivide, objects_by, flip.
    // objects_by="field:NAME" (a meshio.Mesh's integer cell-data array) is stored in *field when
    // given, else refused.
    void read_scene_options(SceneOptions& o, std::string* field = nullptr);
    // The first of those present, or "" (they are refused beside a Scene object).
    std::string scene_option_given() const;
    // method, resolution, backend, threads, rotate / no_rotate, seed, rays, correct, near_k,
    // far_field, and enforce when `enforce` (form_factors only).
    void read_row_options(RowOptions& o, bool enforce);
    // solver, tolerance, max_iterations, overshoot (a number, or True for the default factor),
    // row_cache_mb.
    void read_solver_options(SolverOptions& o);
    // A bool keyword (quiet, allow_unconverged, ...), or fallback when absent.
    bool flag(const std::string& name, bool fallback);
    // TypeError for any keyword none of the reads above took.
    void finish() const;
    // Any other keyword: its value, or None when absent (recorded as accepted either way).
    pybind11::object value(const std::string& name) { return take(name); }
    // A number keyword, or nullopt when absent or None; TypeError naming it otherwise.
    std::optional<double> optional_number(const std::string& name);
    // A path keyword (str or os.PathLike), or "" when absent or None; TypeError naming it otherwise.
    std::string optional_path(const std::string& name);

private:
    // The value of a keyword, or None when absent; records the name as accepted either way.
    pybind11::object take(const std::string& name);
    std::string word(const std::string& name, const pybind11::object& value) const;
    double number(const std::string& name, const pybind11::object& value) const;
    // An integer in [lo, hi]; InputError with the command line's option name otherwise.
    unsigned long long integer(const std::string& name, const pybind11::object& value, long long lo,
                               unsigned long long hi) const;
    bool boolean(const std::string& name, const pybind11::object& value) const;

    pybind11::dict kwargs_;
    std::string function_;
    std::vector<std::string> accepted_;
    std::set<std::string> used_;
};

// The scene argument: a path as str or os.PathLike, or None (the built-in Cornell box: "").
std::string path_argument(const pybind11::object& what, const char* function);

// "--max-patch-edge" for "max_patch_edge": the name messages use.
std::string cli_name(const std::string& keyword);

}  // namespace ffcube::python
