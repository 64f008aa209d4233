// Meshes given as arrays (fe_cells.hpp): checked here, then built in Gmsh's model API in the
// guarded child and collected by the same code as a .msh file (gmsh_collector.hpp).
#include "ffcube/scene/fe_cells.hpp"

#include <fcntl.h>
#include <fmt/format.h>
#include <gmsh.h>
#include <unistd.h>

#include <array>
#include <cmath>
#include <map>
#include <set>
#include <tuple>

#include "ffcube/core/error.hpp"
#include "scene/gmsh_collector.hpp"
#include "scene/model_wire.hpp"

namespace ffcube {
namespace {

constexpr double kMaxCoordinate = 1e15;  // as for a mesh file (gmsh_collector.cpp)

struct CellType {
    const char* name;
    int gmsh_type;
    int dim;
    std::size_t nodes;
    // Gmsh's node k is meshio's node order[k] (meshio keeps VTK's order, which differs from
    // Gmsh's in the quadratic volume cells below; the table is meshio's own, from its Gmsh writer,
    // meshio/gmsh/common.py: _meshio_to_gmsh_order); empty: the same order.
    std::vector<int> order;
};

const std::vector<CellType>& cell_types() {
    static const std::vector<CellType> types = {
        {"triangle", 2, 2, 3, {}},
        {"quad", 3, 2, 4, {}},
        {"triangle6", 9, 2, 6, {}},
        {"quad8", 16, 2, 8, {}},
        {"quad9", 10, 2, 9, {}},
        {"tetra", 4, 3, 4, {}},
        {"hexahedron", 5, 3, 8, {}},
        {"wedge", 6, 3, 6, {}},
        {"pyramid", 7, 3, 5, {}},
        {"tetra10", 11, 3, 10, {0, 1, 2, 3, 4, 5, 6, 7, 9, 8}},
        {"hexahedron20", 17, 3, 20, {0, 1, 2, 3, 4, 5, 6, 7, 8, 11, 16, 9, 17, 10, 18, 19, 12, 15, 13, 14}},
        {"hexahedron27", 12, 3, 27, {0, 1, 2, 3, 4, 5, 6, 7, 8, 11, 16, 9, 17, 10, 18, 19, 12, 15, 13, 14, 24, 22, 20, 21, 23, 25, 26}},
        {"wedge15", 18, 3, 15, {0, 1, 2, 3, 4, 5, 6, 8, 12, 7, 13, 14, 9, 11, 10}},
        {"wedge18", 13, 3, 18, {}},
        {"pyramid13", 19, 3, 13, {0, 1, 2, 3, 4, 5, 8, 9, 6, 10, 7, 11, 12}},
        {"pyramid14", 14, 3, 14, {}},
    };
    return types;
}

const CellType* find_type(const std::string& name) {
    for (const CellType& t : cell_types())
        if (name == t.name) return &t;
    return nullptr;
}

std::string known_types() {
    std::string s;
    for (const CellType& t : cell_types()) s += (s.empty() ? "" : ", ") + std::string(t.name);
    return s;
}

void check(const FeCells& m) {
    for (std::size_t i = 0; i < m.points.size(); ++i)
        for (int r = 0; r < 3; ++r)
            if (!std::isfinite(m.points[i][r]) || std::abs(m.points[i][r]) > kMaxCoordinate)
                throw InputError(fmt::format("{}: points[{}]: coordinate {} is not finite with magnitude at most 1e15", m.source, i,
                                             m.points[i][r]));
    for (const std::string& g : m.groups)
        if (g.empty()) throw InputError(fmt::format("{}: a group has an empty name", m.source));
    for (std::size_t b = 0; b < m.blocks.size(); ++b) {
        const FeCellBlock& block = m.blocks[b];
        const std::string where = fmt::format("{}: cells[{}] ('{}')", m.source, b, block.type);
        const FeCellKind kind = fe_cell_kind(block.type);
        if (kind == FeCellKind::skipped) continue;
        if (kind == FeCellKind::unknown)
            throw InputError(fmt::format("{}: ffcube does not read this cell type (it reads {}; vertex and line cells are skipped)",
                                         where, known_types()));
        const CellType& t = *find_type(block.type);
        if (block.width != t.nodes || block.nodes.size() % t.nodes != 0)
            throw InputError(fmt::format("{}: its cells have {} nodes; a {} cell has {}", where, block.width, block.type, t.nodes));
        const std::size_t n = block.cells();
        if ((!block.group.empty() && block.group.size() != n) || (!block.entity.empty() && block.entity.size() != n))
            throw InputError(fmt::format("{}: its group or entity array has {} values for {} cells", where,
                                         block.group.empty() ? block.entity.size() : block.group.size(), n));
        for (std::size_t k = 0; k < block.nodes.size(); ++k)
            if (block.nodes[k] < 0 || std::uint64_t(block.nodes[k]) >= m.points.size())
                throw InputError(fmt::format("{}: cell {} refers to point {}, which does not exist (the mesh has {} points, 0 to {})",
                                             where, k / t.nodes, block.nodes[k], m.points.size(),
                                             static_cast<long long>(m.points.size()) - 1));
        for (const std::int32_t g : block.group)
            if (g < -1 || (g >= 0 && std::size_t(g) >= m.groups.size()))
                throw InputError(fmt::format("{}: a group index {} out of range", where, g));
    }
}

// In the child: the model in Gmsh, then the faces as bytes.
std::string build_and_collect(const FeCells& m, const FeLoadOptions& options) {
    // Gmsh writes a line to stdout at its start, which may be ffcube's output: silence it here.
    const int devnull = ::open("/dev/null", O_WRONLY | O_CLOEXEC);
    if (devnull >= 0) ::dup2(devnull, 1);
    gmsh::initialize(0, nullptr, false);
    gmsh::option::setNumber("General.Terminal", 0);
    gmsh::option::setNumber("General.NumThreads", 1);
    gmsh::logger::start();
    gmsh::model::add("cells");
    // One discrete entity per (dimension, geometric entity or block, group): a physical group in
    // Gmsh holds whole entities. An entity keeps its gmsh:geometrical tag while that tag has one group.
    long long largest = 0;
    for (const FeCellBlock& b : m.blocks)
        for (const std::int64_t e : b.entity) largest = std::max<long long>(largest, e);
    const bool keep_tags = largest < 1000000000;  // else the tags are numbered anew
    if (!keep_tags) largest = 0;
    std::map<std::tuple<int, long long, int>, int> entity_of;  // (dim, key, group) -> tag
    std::array<std::set<int>, 4> used;
    std::array<int, 4> next{int(largest) + 1, int(largest) + 1, int(largest) + 1, int(largest) + 1};
    struct Elements {
        std::map<int, std::pair<std::vector<std::size_t>, std::vector<std::size_t>>> by_type;  // type -> (tags, nodes)
    };
    std::map<std::pair<int, int>, Elements> entities;  // (dim, tag)
    std::map<std::pair<int, int>, std::vector<int>> group_entities;  // (dim, group) -> tags
    std::size_t element = 0;
    for (std::size_t bi = 0; bi < m.blocks.size(); ++bi) {
        const FeCellBlock& b = m.blocks[bi];
        const CellType* t = find_type(b.type);
        if (!t) {
            element += b.cells();
            continue;
        }
        for (std::size_t c = 0; c < b.cells(); ++c) {
            ++element;
            const long long key = b.entity.empty() || !keep_tags ? -static_cast<long long>(bi) - 1 : b.entity[c];
            const int group = b.group.empty() ? -1 : b.group[c];
            auto [it, inserted] = entity_of.emplace(std::tuple{t->dim, key, group}, 0);
            if (inserted) {
                it->second = key > 0 && used[t->dim].insert(int(key)).second ? int(key) : next[t->dim]++;
                if (group >= 0) group_entities[{t->dim, group}].push_back(it->second);
            }
            auto& [tags, nodes] = entities[{t->dim, it->second}].by_type[t->gmsh_type];
            tags.push_back(element);
            const std::int64_t* n = b.nodes.data() + c * t->nodes;
            for (std::size_t k = 0; k < t->nodes; ++k) nodes.push_back(std::size_t(n[t->order.empty() ? k : std::size_t(t->order[k])]) + 1);
        }
    }
    // The nodes live on an entity of their own, which has no elements.
    const int holder = next[2]++;
    gmsh::model::addDiscreteEntity(2, holder);
    std::vector<std::size_t> node_tags(m.points.size());
    std::vector<double> coords(3 * m.points.size());
    for (std::size_t i = 0; i < m.points.size(); ++i) {
        node_tags[i] = i + 1;
        for (int r = 0; r < 3; ++r) coords[3 * i + std::size_t(r)] = m.points[i][r];
    }
    gmsh::model::mesh::addNodes(2, holder, node_tags, coords);
    for (const auto& [where, els] : entities) {
        gmsh::model::addDiscreteEntity(where.first, where.second);
        for (const auto& [type, tn] : els.by_type) gmsh::model::mesh::addElementsByType(where.second, type, tn.first, tn.second);
    }
    for (const auto& [dg, tags] : group_entities) {
        const int g = gmsh::model::addPhysicalGroup(dg.first, tags);
        gmsh::model::setPhysicalName(dg.first, g, m.groups[std::size_t(dg.second)]);
    }
    std::string last;
    gmsh::logger::getLastError(last);
    if (!last.empty()) throw InputError(fmt::format("{}: Gmsh refused the cells: {}", m.source, last));
    return detail::encode_imported(collect_gmsh_model(m.source, options, false, false), ImportedMaterials{});
}

}  // namespace

FeCellKind fe_cell_kind(const std::string& type) {
    if (find_type(type)) return FeCellKind::read;
    if (type == "vertex" || type.starts_with("line")) return FeCellKind::skipped;
    return FeCellKind::unknown;
}

ObjModel load_fe_cells(const FeCells& cells, const FeLoadOptions& options) {
    check(cells);
    std::uint64_t bytes = 24 * cells.points.size();
    for (const FeCellBlock& b : cells.blocks) bytes += 8 * b.nodes.size();
    return run_gmsh_child(cells.source, bytes, [&]() -> std::string {
        try {
            return build_and_collect(cells, options);
        } catch (const Error&) {
            throw;
        } catch (const std::string& s) {
            throw InputError(fmt::format("{}: Gmsh refused the cells: {}", cells.source, s));
        } catch (const std::exception& e) {
            throw InputError(fmt::format("{}: Gmsh refused the cells: {}", cells.source, e.what()));
        }
    });
}

}  // namespace ffcube
