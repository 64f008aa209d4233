// Legacy VTK (vtk_legacy.hpp): a cursor over the file's bytes that checks every count against
// what is left before it allocates, and the cells handed on as FeCells.
#include "ffcube/scene/vtk_legacy.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <map>
#include <optional>
#include <vector>

#include "ffcube/core/error.hpp"

namespace ffcube {
namespace {

// A VTK data type: its bytes in a BINARY file, and whether its values are integers.
struct DataType {
    std::size_t bytes = 0;
    bool integer = false, is_signed = true, bit = false;
};

std::optional<DataType> data_type(std::string_view t) {
    if (t == "bit") return DataType{0, true, false, true};
    if (t == "unsigned_char") return DataType{1, true, false};
    if (t == "char") return DataType{1, true, true};
    if (t == "unsigned_short") return DataType{2, true, false};
    if (t == "short") return DataType{2, true, true};
    if (t == "unsigned_int" || t == "vtktypeuint32") return DataType{4, true, false};
    if (t == "int" || t == "vtktypeint32") return DataType{4, true, true};
    if (t == "unsigned_long" || t == "vtktypeuint64") return DataType{8, true, false};
    if (t == "long" || t == "vtktypeint64") return DataType{8, true, true};
    if (t == "float") return DataType{4, false, true};
    if (t == "double") return DataType{8, false, true};
    return std::nullopt;
}

// VTK cell type -> meshio's name, its node count (0: any, for skipped kinds) and, for the linear
// wedge, meshio's node order (meshio takes Gmsh's prism order, VTK's wedge wound the other way).
struct VtkCell {
    int vtk;
    const char* name;
    std::size_t nodes;
};
constexpr VtkCell kCells[] = {
    {1, "vertex", 1},        {2, "vertex", 0},         {3, "line", 2},          {4, "line", 0},           {21, "line3", 3},
    {35, "line4", 4},        {5, "triangle", 3},       {9, "quad", 4},          {22, "triangle6", 6},     {23, "quad8", 8},
    {28, "quad9", 9},        {10, "tetra", 4},         {12, "hexahedron", 8},   {13, "wedge", 6},         {14, "pyramid", 5},
    {24, "tetra10", 10},     {25, "hexahedron20", 20}, {29, "hexahedron27", 27}, {26, "wedge15", 15},     {32, "wedge18", 18},
    {27, "pyramid13", 13},
};

const VtkCell* vtk_cell(std::int64_t type) {
    for (const VtkCell& c : kCells)
        if (c.vtk == type) return &c;
    return nullptr;
}

class Reader {
public:
    Reader(std::string_view bytes, const std::string& source) : s_(bytes), source_(source) {}

    [[noreturn]] void fail(const std::string& why) const {
        if (binary_)  // binary data holds newline bytes: a line number would not be the line an editor shows
            throw InputError(fmt::format("{}: byte {}: {}", source_, at_, why));
        const std::size_t line = std::size_t(std::count(s_.begin(), s_.begin() + std::ptrdiff_t(std::min(at_, s_.size())), '\n')) + 1;
        throw InputError(fmt::format("{}: line {}: {}", source_, line, why));
    }

    bool at_end() {
        skip_space();
        return at_ >= s_.size();
    }

    // The next whitespace-separated word ("" at the end of the file).
    std::string_view word() {
        skip_space();
        const std::size_t begin = at_;
        while (at_ < s_.size() && !space(s_[at_])) ++at_;
        return s_.substr(begin, at_ - begin);
    }
    std::string_view peek() {
        const std::size_t keep = at_;
        const std::string_view w = word();
        at_ = keep;
        return w;
    }
    std::string_view line() {
        const std::size_t begin = at_;
        while (at_ < s_.size() && s_[at_] != '\n') ++at_;
        const std::string_view l = s_.substr(begin, at_ - begin);
        if (at_ < s_.size()) ++at_;
        return l;
    }
    // After the word METADATA: the rest of its line, then its lines up to an empty one (VTK's
    // INFORMATION and COMPONENT_NAMES blocks).
    void skip_metadata() {
        line();
        while (at_ < s_.size()) {
            std::string_view l = line();
            while (!l.empty() && space(l.back())) l.remove_suffix(1);
            if (l.empty()) break;
        }
    }
    std::string_view expect(std::string_view keyword, const char* what) {
        const std::string_view w = word();
        if (w != keyword) fail(fmt::format("expected {} ({}), found '{}'", keyword, what, shorten(w)));
        return w;
    }

    // A count: a non-negative integer of at most `limit`.
    std::uint64_t count(const char* what, std::uint64_t limit) {
        const std::string_view w = word();
        std::uint64_t v = 0;
        const auto [p, ec] = std::from_chars(w.data(), w.data() + w.size(), v);
        if (w.empty() || ec != std::errc() || p != w.data() + w.size())
            fail(fmt::format("{}: '{}' is not a count (a non-negative integer)", what, shorten(w)));
        if (v > limit) fail(fmt::format("{}: {} is more than the rest of the file can hold", what, v));
        return v;
    }
    DataType type(const char* what) {
        const std::string_view w = word();
        const std::optional<DataType> t = data_type(w);
        if (!t) fail(fmt::format("{}: '{}' is not a VTK data type (bit, char, short, int, long, their unsigned_ kinds, float, double, "
                                 "vtktypeint32/64)",
                                 what, shorten(w)));
        return *t;
    }

    // The most values of `t` the rest of the file can hold (ASCII: a digit and a separator each).
    std::uint64_t room(const DataType& t) const {
        const std::uint64_t left = s_.size() - std::min(at_, s_.size());
        if (!binary_) return left / 2 + 1;
        return t.bit ? left * 8 : left / t.bytes;
    }

    // `n` values of type `t`: as doubles (`out` non-null), else skipped. `integers`: each must be
    // an integer (ASCII) and the type an integer type.
    void values(std::uint64_t n, const DataType& t, std::vector<double>* out, const char* what) {
        if (n > room(t)) fail(fmt::format("{}: {} values are more than the rest of the file holds", what, n));
        if (out) out->reserve(std::size_t(n));
        if (binary_) {
            while (at_ < s_.size() && s_[at_] != '\n') ++at_;  // the rest of the keyword's line, as VTK's reader
            if (at_ < s_.size()) ++at_;
            if (t.bit) {
                const std::size_t bytes = std::size_t((n + 7) / 8);
                if (bytes > s_.size() - at_) fail(fmt::format("{}: the file ends inside its {} values", what, n));
                for (std::uint64_t k = 0; out && k < n; ++k)
                    out->push_back(double((std::uint8_t(s_[at_ + k / 8]) >> (7 - k % 8)) & 1));
                at_ += bytes;
            } else {
                if (n * t.bytes > s_.size() - at_) fail(fmt::format("{}: the file ends inside its {} values", what, n));
                for (std::uint64_t k = 0; out && k < n; ++k) out->push_back(big_endian(at_ + k * t.bytes, t));
                at_ += std::size_t(n * t.bytes);
            }
            return;
        }
        for (std::uint64_t k = 0; k < n; ++k) {
            const std::string_view w = word();
            double v = 0.0;
            const auto [p, ec] = std::from_chars(w.data(), w.data() + w.size(), v);
            if (w.empty() || ec != std::errc() || p != w.data() + w.size())
                fail(fmt::format("{}: value {} of {}: '{}' is not a number", what, k, n, shorten(w)));
            if (t.integer && v != std::floor(v))
                fail(fmt::format("{}: value {} of {}: '{}' is not an integer", what, k, n, shorten(w)));
            if (out) out->push_back(v);
        }
    }

    // Integer values that must lie in [0, limit] (cells, offsets, types, point indices).
    std::vector<std::int64_t> indices(std::uint64_t n, const DataType& t, const char* what) {
        if (!t.integer) fail(fmt::format("{}: its values must be of an integer type", what));
        std::vector<double> v;
        values(n, t, &v, what);
        std::vector<std::int64_t> out(v.size());
        for (std::size_t k = 0; k < v.size(); ++k) {
            if (!(v[k] >= 0.0 && v[k] <= 9.0e15)) fail(fmt::format("{}: value {} is {}, not an index", what, k, v[k]));
            out[k] = std::int64_t(v[k]);
        }
        return out;
    }

    bool binary_ = false;

private:
    static bool space(char c) { return c == ' ' || c == '\t' || c == '\r' || c == '\n' || c == '\f' || c == '\v'; }
    void skip_space() {
        while (at_ < s_.size() && space(s_[at_])) ++at_;
    }
    static std::string shorten(std::string_view w) {
        std::string out(w.substr(0, 40));
        for (char& c : out)
            if (static_cast<unsigned char>(c) < 32 || static_cast<unsigned char>(c) > 126) c = '?';
        return w.size() > 40 ? out + "..." : out;
    }
    double big_endian(std::size_t at, const DataType& t) const {
        std::uint64_t u = 0;
        for (std::size_t k = 0; k < t.bytes; ++k) u = (u << 8) | std::uint8_t(s_[at + k]);
        if (!t.integer) {
            if (t.bytes == 4) {
                float f;
                const std::uint32_t v = std::uint32_t(u);
                std::memcpy(&f, &v, 4);
                return double(f);
            }
            double d;
            std::memcpy(&d, &u, 8);
            return d;
        }
        if (!t.is_signed) return double(u);
        const int shift = int(64 - 8 * t.bytes);
        return double(std::int64_t(u << shift) >> shift);  // sign-extended
    }

    std::string_view s_;
    const std::string& source_;
    std::size_t at_ = 0;
};

}  // namespace

int vtk_legacy_version(std::string_view bytes) {
    constexpr std::string_view head = "# vtk DataFile Version ";
    if (!bytes.starts_with(head)) return -1;
    int major = -1;
    const char* p = bytes.data() + head.size();
    const auto [end, ec] = std::from_chars(p, bytes.data() + std::min(bytes.size(), head.size() + 8), major);
    return ec == std::errc() && end != p ? major : -1;
}

FeCells read_vtk_legacy(std::string_view bytes, const std::string& source, const std::string& field) {
    Reader in(bytes, source);
    const int version = vtk_legacy_version(bytes);
    if (version < 0) in.fail("not a legacy VTK file (its first line must be '# vtk DataFile Version x.y')");
    in.line();
    in.line();  // the title
    std::string_view mode = in.line();
    while (!mode.empty() && (mode.back() == '\r' || mode.back() == ' ' || mode.back() == '\t')) mode.remove_suffix(1);
    if (mode == "BINARY")
        in.binary_ = true;
    else if (mode != "ASCII")
        in.fail(fmt::format("line 3 must be ASCII or BINARY"));
    in.expect("DATASET", "the dataset's kind");
    const std::string_view dataset = in.word();
    if (dataset != "UNSTRUCTURED_GRID")
        in.fail(fmt::format("DATASET {}: ffcube's VTK reader reads UNSTRUCTURED_GRID (without --objects-by field:NAME, Gmsh reads "
                            "version 4.2 and older POLYDATA)",
                            dataset));

    FeCells out;
    out.source = source;
    std::vector<double> points;
    std::vector<std::int64_t> connectivity, offsets, types;  // offsets: ncells + 1, into connectivity
    bool have_points = false, have_cells = false, have_types = false;
    std::optional<std::vector<double>> groups;
    std::uint64_t attribute_count = 0;  // per value of the current CELL_DATA or POINT_DATA
    bool cell_data = false;
    const auto cells = [&] { return offsets.empty() ? std::uint64_t(0) : std::uint64_t(offsets.size() - 1); };
    // One attribute array of `per` values per point or cell: kept when it is the field.
    const auto array = [&](const std::string_view name, std::uint64_t per, const DataType& t, const char* what) {
        if (!cell_data || name != field) return in.values(per * attribute_count, t, nullptr, what);
        if (per != 1) in.fail(fmt::format("the cell array '{}' has {} components; --objects-by field:{} takes one integer per cell", name, per, field));
        if (!t.integer || t.bit)
            in.fail(fmt::format("the cell array '{}' is not of an integer type; --objects-by field:{} takes one integer per cell", name, field));
        groups.emplace();
        in.values(attribute_count, t, &*groups, what);
    };
    while (!in.at_end()) {
        const std::string_view key = in.word();
        if (key == "POINTS") {
            const std::uint64_t n = in.count("POINTS", std::uint64_t(1) << 40);
            const DataType t = in.type("POINTS");
            if (n > in.room(t) / 3) in.fail(fmt::format("POINTS {}: more points than the rest of the file holds", n));
            points.clear();
            in.values(3 * n, t, &points, "POINTS");
            have_points = true;
        } else if (key == "CELLS") {
            const std::uint64_t a = in.count("CELLS", std::uint64_t(1) << 40), b = in.count("CELLS", std::uint64_t(1) << 42);
            if (version >= 5) {  // a = cells + 1 offsets, b = connectivity entries
                in.expect("OFFSETS", "version 5 cells");
                offsets = in.indices(a, in.type("OFFSETS"), "OFFSETS");
                in.expect("CONNECTIVITY", "version 5 cells");
                connectivity = in.indices(b, in.type("CONNECTIVITY"), "CONNECTIVITY");
                if (offsets.empty() || offsets.front() != 0 || std::uint64_t(offsets.back()) != b ||
                    !std::is_sorted(offsets.begin(), offsets.end()))
                    in.fail(fmt::format("CELLS {} {}: OFFSETS must rise from 0 to {}", a, b, b));
            } else {  // a cells, b integers: each cell its node count, then its nodes
                const std::vector<std::int64_t> list = in.indices(b, DataType{4, true, true}, "CELLS");
                offsets.assign(1, 0);
                connectivity.clear();
                std::size_t k = 0;
                for (std::uint64_t c = 0; c < a; ++c) {
                    if (k >= list.size() || std::uint64_t(list[k]) > list.size() - k - 1)
                        in.fail(fmt::format("CELLS {} {}: cell {} runs past the {} integers", a, b, c, b));
                    const std::size_t m = std::size_t(list[k]);
                    connectivity.insert(connectivity.end(), list.begin() + std::ptrdiff_t(k + 1), list.begin() + std::ptrdiff_t(k + 1 + m));
                    k += m + 1;
                    offsets.push_back(std::int64_t(connectivity.size()));
                }
                if (k != list.size()) in.fail(fmt::format("CELLS {} {}: its cells take {} of the {} integers", a, b, k, b));
            }
            have_cells = true;
        } else if (key == "CELL_TYPES") {
            const std::uint64_t n = in.count("CELL_TYPES", std::uint64_t(1) << 40);
            types = in.indices(n, DataType{4, true, true}, "CELL_TYPES");
            have_types = true;
        } else if (key == "CELL_DATA" || key == "POINT_DATA") {
            cell_data = key == "CELL_DATA";
            attribute_count = in.count(cell_data ? "CELL_DATA" : "POINT_DATA", std::uint64_t(1) << 40);
            const std::uint64_t expected = cell_data ? cells() : points.size() / 3;
            if (!have_points || !have_cells || attribute_count != expected)
                in.fail(fmt::format("{} {}: the file has {} {} before it", key, attribute_count, expected, cell_data ? "cells" : "points"));
        } else if (key == "SCALARS") {
            const std::string name(in.word());
            const DataType t = in.type("SCALARS");
            // "SCALARS name type [components]", then "LOOKUP_TABLE table" (which VTK's reader requires).
            const std::uint64_t components = in.peek() == "LOOKUP_TABLE" ? 1 : in.count("SCALARS components", 4);
            in.expect("LOOKUP_TABLE", "after SCALARS");
            in.word();
            array(name, components, t, "SCALARS");
        } else if (key == "VECTORS" || key == "NORMALS" || key == "TENSORS" || key == "TENSORS6") {
            const std::string name(in.word());
            array(name, key == "TENSORS" ? 9 : key == "TENSORS6" ? 6 : 3, in.type(key == "VECTORS" ? "VECTORS" : "NORMALS"), "VECTORS");
        } else if (key == "TEXTURE_COORDINATES") {
            const std::string name(in.word());
            const std::uint64_t dim = in.count("TEXTURE_COORDINATES", 3);
            array(name, dim, in.type("TEXTURE_COORDINATES"), "TEXTURE_COORDINATES");
        } else if (key == "COLOR_SCALARS") {
            const std::string name(in.word());
            const std::uint64_t n = in.count("COLOR_SCALARS", 4);
            array(name, n, in.binary_ ? DataType{1, true, false} : DataType{4, false, true}, "COLOR_SCALARS");
        } else if (key == "LOOKUP_TABLE") {
            in.word();
            const std::uint64_t n = in.count("LOOKUP_TABLE", std::uint64_t(1) << 32);
            in.values(4 * n, in.binary_ ? DataType{1, true, false} : DataType{4, false, true}, nullptr, "LOOKUP_TABLE");
        } else if (key == "FIELD") {
            in.word();
            const std::uint64_t arrays = in.count("FIELD", 1u << 20);
            for (std::uint64_t k = 0; k < arrays; ++k) {
                const std::string name(in.word());
                const std::uint64_t components = in.count("FIELD array components", 1u << 16);
                const std::uint64_t tuples = in.count("FIELD array tuples", std::uint64_t(1) << 40);
                const DataType t = in.type("FIELD array");
                if (attribute_count != 0 && tuples == attribute_count) {
                    array(name, components, t, "FIELD array");
                } else {  // the dataset's own field data, or an array of another length: skipped
                    if (components != 0 && tuples > in.room(t) / components) in.fail(fmt::format("FIELD array '{}': too long for the file", name));
                    in.values(components * tuples, t, nullptr, "FIELD array");
                }
                if (in.peek() == "METADATA") in.word(), in.skip_metadata();
            }
        } else if (key == "METADATA") {
            in.skip_metadata();
        } else {
            in.fail(fmt::format("'{}' is not a keyword ffcube's VTK reader reads", key.substr(0, 40)));
        }
    }
    if (!have_points || !have_cells || !have_types) in.fail("the file ends without its POINTS, CELLS and CELL_TYPES");
    if (types.size() != cells()) in.fail(fmt::format("CELL_TYPES has {} types for {} cells", types.size(), cells()));
    if (!field.empty() && !groups)
        throw InputError(fmt::format("{}: --objects-by field:{}: the file has no cell array '{}' (CELL_DATA, SCALARS or FIELD)", source,
                                     field, field));

    const std::size_t npoints = points.size() / 3;
    out.points.resize(npoints);
    for (std::size_t i = 0; i < npoints; ++i) out.points[i] = Vec3(points[3 * i], points[3 * i + 1], points[3 * i + 2]);
    std::map<std::int64_t, std::int32_t> group_of_value;
    for (std::size_t c = 0; c < types.size(); ++c) {
        const VtkCell* t = vtk_cell(types[c]);
        if (!t) {
            std::string known;
            for (const VtkCell& k : kCells) known += fmt::format("{}{} ({})", known.empty() ? "" : ", ", k.vtk, k.name);
            throw InputError(fmt::format("{}: cell {} is of VTK type {}, which ffcube does not read (it reads {})", source, c, types[c], known));
        }
        const std::size_t begin = std::size_t(offsets[c]), m = std::size_t(offsets[c + 1]) - begin;
        if (m == 0) throw InputError(fmt::format("{}: cell {} (VTK type {}) has no nodes", source, c, types[c]));
        if (t->nodes != 0 && m != t->nodes)
            throw InputError(fmt::format("{}: cell {} ({}, VTK type {}) has {} nodes; a {} has {}", source, c, t->name, t->vtk, m, t->name, t->nodes));
        for (std::size_t k = 0; k < m; ++k)
            if (std::uint64_t(connectivity[begin + k]) >= npoints)
                throw InputError(fmt::format("{}: cell {} refers to point {}, which does not exist (the file has {} points, 0 to {})", source,
                                             c, connectivity[begin + k], npoints, std::int64_t(npoints) - 1));
        if (out.blocks.empty() || out.blocks.back().type != t->name || out.blocks.back().width != m) {
            FeCellBlock b;
            b.type = t->name;
            b.width = m;
            out.blocks.push_back(std::move(b));
        }
        FeCellBlock& b = out.blocks.back();
        const bool wedge = t->vtk == 13;
        for (std::size_t k = 0; k < m; ++k) {
            static constexpr std::size_t kWedge[6] = {0, 2, 1, 3, 5, 4};  // meshio's (Gmsh's) prism order
            b.nodes.push_back(connectivity[begin + (wedge ? kWedge[k] : k)]);
        }
        if (fe_cell_kind(b.type) != FeCellKind::read) continue;
        b.entity.push_back(1);  // one entity per dimension, as Gmsh reads a .vtk
        if (groups) {
            const double v = (*groups)[c];
            const auto [it, inserted] = group_of_value.emplace(std::int64_t(v), std::int32_t(out.groups.size()));
            if (inserted) out.groups.push_back(fmt::format("{}_{}", field, std::int64_t(v)));
            b.group.push_back(it->second);
        }
    }
    return out;
}

}  // namespace ffcube
