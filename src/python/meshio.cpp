// load_scene(meshio.Mesh) and Scene.cell_data (module.hpp): the mesh's arrays become FeCells
// (scene/fe_cells.hpp), read by the same code as a mesh file read through Gmsh.
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <fmt/format.h>

#include <cmath>
#include <limits>
#include <map>
#include <string>
#include <vector>

#include "ffcube/core/error.hpp"
#include "ffcube/core/timer.hpp"
#include "ffcube/scene/fe_cells.hpp"
#include "module.hpp"

namespace ffcube::python {
namespace {

constexpr const char* kSource = "meshio.Mesh";

std::string type_name(const py::handle& v) { return py::str(v.get_type().attr("__name__")); }

// One integer per cell of block b: a 1-D (or n x 1) array of an integer dtype.
std::vector<std::int64_t> integers_per_cell(const py::object& values, std::size_t b, const std::string& what, std::size_t cells,
                                            const std::string& block_type) {
    const py::array a = py::module_::import("numpy").attr("asarray")(values);
    const char kind = a.dtype().kind();
    const bool shape_ok = (a.ndim() == 1 && std::size_t(a.shape(0)) == cells) ||
                          (a.ndim() == 2 && std::size_t(a.shape(0)) == cells && a.shape(1) == 1);
    if ((kind != 'i' && kind != 'u' && !(kind == 'f' && cells == 0)) || !shape_ok)
        throw InputError(fmt::format("{}: {}[{}] (cells[{}], '{}'): must hold one integer per cell ({} cells), not an array of dtype "
                                     "{} and shape {}",
                                     kSource, what, b, b, block_type, cells, std::string(py::str(a.dtype())),
                                     std::string(py::str(a.attr("shape")))));
    const py::array_t<std::int64_t, py::array::c_style | py::array::forcecast> v(a.attr("reshape")(-1));
    return {v.data(), v.data() + v.size()};
}

int block_dim(const std::string& type) {
    return type.starts_with("tetra") || type.starts_with("hexahedron") || type.starts_with("wedge") || type.starts_with("pyramid") ? 3 : 2;
}

// The group index of every cell: from cell_sets (those not named gmsh:*), else from an integer
// cell-data array (`field`, or gmsh:physical), named through field_data ({name: [tag, dim]}).
void read_groups(const py::object& mesh, const std::string& field, FeCells& out) {
    std::map<std::string, std::int32_t> index;
    const auto group = [&](const std::string& name) {
        const auto [it, inserted] = index.emplace(name, static_cast<std::int32_t>(out.groups.size()));
        if (inserted) out.groups.push_back(name);
        return it->second;
    };
    const py::dict cell_data = py::hasattr(mesh, "cell_data") ? py::dict(mesh.attr("cell_data")) : py::dict();
    const py::dict field_data = py::hasattr(mesh, "field_data") ? py::dict(mesh.attr("field_data")) : py::dict();
    const py::dict cell_sets = py::hasattr(mesh, "cell_sets") ? py::dict(mesh.attr("cell_sets")) : py::dict();
    std::string array = field;
    if (array.empty()) {
        // cell_sets first (gmsh:bounding_entities and other gmsh:* sets are not groups).
        std::vector<std::vector<std::string>> named(out.blocks.size());
        bool any = false;
        for (const auto& [key, value] : cell_sets) {
            const std::string name = py::str(key);
            if (name.starts_with("gmsh:")) continue;
            const py::list per_block(py::reinterpret_borrow<py::object>(value));
            if (per_block.size() != out.blocks.size())
                throw InputError(fmt::format("{}: cell_sets['{}'] has {} entries for {} cell blocks", kSource, name, per_block.size(),
                                             out.blocks.size()));
            for (std::size_t b = 0; b < out.blocks.size(); ++b) {
                if (per_block[b].is_none()) continue;
                FeCellBlock& block = out.blocks[b];
                const std::size_t cells = block.cells();
                const py::array_t<std::int64_t, py::array::c_style | py::array::forcecast> ids(
                    py::module_::import("numpy").attr("asarray")(per_block[b]).attr("reshape")(-1));
                if (ids.size() == 0) continue;
                if (block.group.empty()) block.group.assign(cells, -1);
                const std::int32_t g = group(name);
                for (py::ssize_t k = 0; k < ids.size(); ++k) {
                    const std::int64_t c = ids.data()[k];
                    if (c < 0 || std::uint64_t(c) >= cells)
                        throw InputError(fmt::format("{}: cell_sets['{}'][{}]: cell {} does not exist (cells[{}], '{}', has {} cells)",
                                                     kSource, name, b, c, b, block.type, cells));
                    std::int32_t& slot = block.group[std::size_t(c)];
                    if (slot >= 0 && slot != g)
                        throw InputError(fmt::format("{}: cells[{}] ('{}'): cell {} is in two cell sets ('{}' and '{}'); a cell may be in "
                                                     "one",
                                                     kSource, b, block.type, c, out.groups[std::size_t(slot)], name));
                    slot = g;
                    any = true;
                }
            }
        }
        if (any) return;
        if (!cell_data.contains("gmsh:physical")) return;
        array = "gmsh:physical";
    }
    if (!cell_data.contains(array.c_str())) {
        std::string names;
        for (const auto& [key, value] : cell_data) names += (names.empty() ? "" : ", ") + std::string(py::str(key));
        throw InputError(fmt::format("{}: objects_by='field:{}': the mesh has no cell data '{}' (it has: {})", kSource, array, array,
                                     names.empty() ? "none" : names));
    }
    const py::list per_block(cell_data[array.c_str()]);
    if (per_block.size() != out.blocks.size())
        throw InputError(fmt::format("{}: cell_data['{}'] has {} entries for {} cell blocks", kSource, array, per_block.size(),
                                     out.blocks.size()));
    // field_data: a name per (value, dimension), as Gmsh's physical names.
    std::map<std::pair<std::int64_t, int>, std::string> names;
    for (const auto& [key, value] : field_data) {
        const py::array_t<std::int64_t, py::array::c_style | py::array::forcecast> v(py::module_::import("numpy").attr("asarray")(value));
        if (v.size() >= 2) names[{v.data()[0], int(v.data()[1])}] = py::str(key);
        else if (v.size() == 1) names[{v.data()[0], 0}] = py::str(key);
    }
    const std::string prefix = array == "gmsh:physical" ? "group" : array;
    for (std::size_t b = 0; b < out.blocks.size(); ++b) {
        FeCellBlock& block = out.blocks[b];
        if (fe_cell_kind(block.type) != FeCellKind::read) continue;
        const std::vector<std::int64_t> v = integers_per_cell(per_block[b], b, "cell_data['" + array + "']", block.cells(), block.type);
        block.group.resize(v.size());
        const int dim = block_dim(block.type);
        for (std::size_t c = 0; c < v.size(); ++c) {
            auto it = names.find({v[c], dim});
            if (it == names.end()) it = names.find({v[c], 0});
            block.group[c] = group(it != names.end() ? it->second : fmt::format("{}_{}", prefix, v[c]));
        }
    }
}

}  // namespace

bool is_meshio_mesh(const py::object& what) {
    return !what.is_none() && !py::isinstance<py::str>(what) && py::hasattr(what, "points") && py::hasattr(what, "cells");
}

PyScene load_meshio(const py::object& mesh, Kwargs& kw) {
    SceneOptions options;
    std::string field;
    kw.read_scene_options(options, &field);
    const bool quiet = kw.flag("quiet", false);
    kw.finish();
    if (options.format != SceneFormat::Auto)
        throw py::type_error("load_scene(): format applies to files; a meshio.Mesh is read as its cells say");
    Stopwatch watch;
    FeCells cells;
    const py::array points = py::module_::import("numpy").attr("asarray")(mesh.attr("points"), "float64");
    if (points.ndim() != 2 || (points.shape(1) != 2 && points.shape(1) != 3))
        throw InputError(fmt::format("{}: points must be an array of shape (n, 2) or (n, 3), not {}", kSource,
                                     std::string(py::str(points.attr("shape")))));
    {
        const py::array_t<double, py::array::c_style | py::array::forcecast> p(points);
        const std::size_t n = std::size_t(p.shape(0)), w = std::size_t(p.shape(1));
        cells.points.resize(n, Vec3(0.0));
        for (std::size_t i = 0; i < n; ++i)
            for (std::size_t r = 0; r < w; ++r) cells.points[i][int(r)] = p.data()[i * w + r];
    }
    std::vector<std::size_t> sizes;
    const py::list blocks(mesh.attr("cells"));
    for (std::size_t b = 0; b < blocks.size(); ++b) {
        const py::object block = blocks[b];
        FeCellBlock fb;
        if (py::hasattr(block, "type") && py::hasattr(block, "data")) {
            fb.type = py::str(block.attr("type"));
        } else {
            throw py::type_error(fmt::format("load_scene(): mesh.cells[{}] is a {}, not a meshio.CellBlock", b, type_name(block)));
        }
        const py::array data = py::module_::import("numpy").attr("asarray")(block.attr("data"));
        const char kind = data.dtype().kind();
        if (fe_cell_kind(fb.type) == FeCellKind::read && (data.ndim() != 2 || (kind != 'i' && kind != 'u')))
            throw InputError(fmt::format("{}: cells[{}] ('{}'): its data must be a 2-D array of point indices, not dtype {} with {} "
                                         "dimensions",
                                         kSource, b, fb.type, std::string(py::str(data.dtype())), data.ndim()));
        if (data.ndim() == 2) {
            const py::array_t<std::int64_t, py::array::c_style | py::array::forcecast> d(data);
            fb.width = std::size_t(d.shape(1));
            fb.nodes.assign(d.data(), d.data() + d.size());
            sizes.push_back(std::size_t(d.shape(0)));
        } else {
            sizes.push_back(data.ndim() == 0 ? 0 : std::size_t(data.shape(0)));  // a skipped block of another shape
            fb.width = 0;
        }
        cells.blocks.push_back(std::move(fb));
    }
    read_groups(mesh, field, cells);
    const py::dict cell_data = py::hasattr(mesh, "cell_data") ? py::dict(mesh.attr("cell_data")) : py::dict();
    if (cell_data.contains("gmsh:geometrical")) {
        const py::list per_block(cell_data["gmsh:geometrical"]);
        for (std::size_t b = 0; b < cells.blocks.size() && b < per_block.size(); ++b)
            if (fe_cell_kind(cells.blocks[b].type) == FeCellKind::read)
                cells.blocks[b].entity =
                    integers_per_cell(per_block[b], b, "cell_data['gmsh:geometrical']", cells.blocks[b].cells(), cells.blocks[b].type);
    }
    const double extract_s = watch.seconds();
    PyScene s;
    s.mesh_blocks = sizes;
    {
        py::gil_scoped_release nogil;
        LogScope log(quiet);
        Stopwatch read;
        Report report;
        ObjModel model = load_fe_cells(cells, fe_load_options(options));
        s.scene = std::make_shared<const Scene>(mesh_model(std::move(model), options, report, "meshio", extract_s + read.seconds()));
        s.load_report = report.dump();
    }
    return s;
}

py::list cell_data_of(const PyScene& s, const py::object& values) {
    const Scene& scene = *s.scene;
    const std::size_t n = scene.size();
    if (s.mesh_blocks.empty())
        throw py::value_error("Scene.cell_data(): this scene was not loaded from a meshio.Mesh (load_scene(mesh))");
    if (scene.patch_elements.size() != n)
        throw py::value_error("Scene.cell_data(): this scene's patches carry no element ids");
    const py::array_t<double, py::array::c_style | py::array::forcecast> v(py::module_::import("numpy").attr("asarray")(values, "float64"));
    if ((v.ndim() != 1 && v.ndim() != 2) || std::size_t(v.shape(0)) != n)
        throw py::value_error(fmt::format("Scene.cell_data(): values must have one row per patch ({} patches), shape ({},) or ({}, k)",
                                          n, n, n));
    const std::size_t k = v.ndim() == 2 ? std::size_t(v.shape(1)) : 1;
    std::size_t total = 0;
    for (const std::size_t b : s.mesh_blocks) total += b;
    // Area-weighted mean over the patches of each cell (a cell split into several patches, or a
    // volume cell with several boundary faces); NaN for a cell with no patch.
    std::vector<double> sum(total * k, 0.0), area(total, 0.0);
    std::vector<std::size_t> count(total, 0), last(total, 0);  // one patch: its value as it is
    for (std::size_t i = 0; i < n; ++i) {
        const std::uint64_t e = scene.patch_elements[i];
        if (e == 0 || e > total) throw InternalError(fmt::format("patch {} has element id {} of {} cells", i, e, total));
        const double a = scene.patches[i].area;
        area[e - 1] += a;
        ++count[e - 1];
        last[e - 1] = i;
        for (std::size_t j = 0; j < k; ++j) sum[(e - 1) * k + j] += a * v.data()[i * k + j];
    }
    py::list out;
    std::size_t first = 0;
    for (const std::size_t cells : s.mesh_blocks) {
        py::array_t<double> a = v.ndim() == 2 ? py::array_t<double>({py::ssize_t(cells), py::ssize_t(k)}) : py::array_t<double>(py::ssize_t(cells));
        double* d = a.mutable_data();
        for (std::size_t c = 0; c < cells; ++c)
            for (std::size_t j = 0; j < k; ++j)
                d[c * k + j] = count[first + c] == 1 ? v.data()[last[first + c] * k + j]
                               : area[first + c] > 0 ? sum[(first + c) * k + j] / area[first + c]
                                                     : std::numeric_limits<double>::quiet_NaN();
        out.append(a);
        first += cells;
    }
    return out;
}

}  // namespace ffcube::python
