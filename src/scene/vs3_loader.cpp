// NIST View3D's input format (.vs3), geometry format 3, as its manual describes it
// (../shared/formats/view3d.md): one element per line, named by the line's first character.
#include "ffcube/scene/vs3_loader.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <cctype>
#include <charconv>
#include <map>
#include <unordered_map>

#include "ffcube/core/error.hpp"
#include "ffcube/scene/load_model.hpp"
#include "text_lines.hpp"
#include "vs3_subsurfaces.hpp"

namespace ffcube {
namespace {

using detail::fail_at;
using detail::shown;

class Vs3Parser {
public:
    Vs3Parser(std::string_view text, const std::string& source)
        : reader_(text, source, "!/", "not a View3D file (control bytes: binary data?)"), source_(source) {
        model_.source = source;
        model_.view3d.present = true;
        model_.materials.push_back(Material{"default", Vec3(0.5), Vec3(0.0)});
    }

    ObjModel run() {
        std::string_view line;
        while (next_line(line)) {
            std::string_view element;
            if (!token(line, element)) continue;
            const char kind = static_cast<char>(std::toupper(static_cast<unsigned char>(element.front())));
            if (kind == 'E' || kind == '*') break;  // end of data: nothing after it is read
            if (element.size() != 1 && kind != 'E')
                fail_at(source_, number_, fmt::format("unknown element {} (View3D lines begin with T, C, F, V, S, O, M, N or E)",
                                                      shown(element)));
            switch (kind) {
            case 'T': model_.view3d.title = std::string(detail::LineReader::trim(line)); break;  // the last one wins
            case 'C': control(line); break;
            case 'F': geometry_format(line); break;
            case 'V': vertex(line); break;
            case 'S':
            case 'O':
            case 'M':
            case 'N': surface(line, kind); break;
            default:
                fail_at(source_, number_, fmt::format("unknown element {} (View3D lines begin with T, C, F, V, S, O, M, N or E)",
                                                      shown(element)));
            }
        }
        for (const Surface& f : surfaces_)
            for (const std::uint32_t v : f.face.v)
                if (v >= model_.positions.size())
                    fail_at(source_, f.face.line,
                            fmt::format("vertex {} is not defined (the file defines {} vertices)", v + 1, model_.positions.size()));
        if (model_.view3d.col != 0 && model_.view3d.row == 0)  // View3D's rule (getdat.c)
            fail_at(source_, model_.view3d.col_line,
                    fmt::format("control col={} needs row (View3D: \"Must set row before setting column\")", model_.view3d.col));
        if (model_.view3d.max_distance > 0.0)
            for (std::size_t n = 0; n < surfaces_.size(); ++n)
                if (surfaces_[n].base != 0)
                    fail_at(source_, model_.view3d.max_distance_line,
                            fmt::format("control maxD with a subsurface, null or masking surface (surface {}, line {}) is not "
                                        "supported: ffcube cuts the base into pieces, whose centroids are not the centroid "
                                        "View3D measures the distance from",
                                        n + 1, surfaces_[n].face.line));
        make_faces();
        if (model_.faces.empty()) throw InputError(fmt::format("{}: no S surfaces: the scene has no geometry", source_));
        append_obstructions();
        if (!saw_format_)
            model_.warnings.push_back(fmt::format("{}: no F line: read as geometry format F 3 (vertices, then surfaces)", source_));
        return std::move(model_);
    }

private:
    bool next_line(std::string_view& line) {
        const bool more = reader_.next(line);
        number_ = reader_.line_number();
        return more;
    }
    bool token(std::string_view& line, std::string_view& out) const { return reader_.token(line, out); }

    std::string_view required(std::string_view& line, const char* what) const { return reader_.required(line, what); }

    long long integer(std::string_view& line, const char* what) {
        const std::string_view t = required(line, what);
        long long v = 0;
        const auto [end, ec] = std::from_chars(t.data(), t.data() + t.size(), v);
        if (ec != std::errc() || end != t.data() + t.size() || v < 0 || v > 0x7fffffff)
            fail_at(source_, number_, fmt::format("{} is not a valid {} (a whole number >= 0)", shown(t), what));
        return v;
    }

    void control(std::string_view line) {
        std::string_view pair;
        while (token(line, pair)) {
            const std::size_t eq = pair.find('=');
            if (eq == std::string_view::npos || eq == 0 || eq + 1 == pair.size())
                fail_at(source_, number_, fmt::format("control {} is not name=value", shown(pair)));
            const std::string key(pair.substr(0, eq));
            const double value = detail::parse_number(pair.substr(eq + 1), source_, number_, "a control value");
            std::string lower = key;
            std::transform(lower.begin(), lower.end(), lower.begin(), [](unsigned char c) { return std::tolower(c); });
            // Honoured: encl, emit (0 or 1 each, as View3D takes them), out (0 text, 1 binary, 2 the
            // forks' sparse text, as View3D 4's getdat.c takes it).
            if (lower == "encl" || lower == "emit") {
                if (value != 0.0 && value != 1.0)
                    fail_at(source_, number_, fmt::format("control {}={} must be 0 or 1", key, value));
                (lower == "encl" ? model_.view3d.encl : model_.view3d.emit) = static_cast<int>(value);
                if (lower == "encl") model_.view3d.encl_line = number_;
                continue;
            }
            if (lower == "out") {
                if (value != 0.0 && value != 1.0 && value != 2.0)
                    fail_at(source_, number_,
                            fmt::format("control {}={} must be 0, 1 or 2 (0 text, 1 binary, 2 sparse text)", key, value));
                model_.view3d.out = static_cast<int>(value);
                continue;
            }
            // Acted on by `ffcube view3d` only (row and col refused there, maxD applied), so they are
            // recorded with their line; the commands that ignore them warn (apply_view3d_controls).
            if (lower == "row" || lower == "col") {
                if (!(value >= 0.0 && value <= 0x7fffffff) || value != static_cast<double>(static_cast<long long>(value)))
                    fail_at(source_, number_, fmt::format("control {}={} must be a surface number (a whole number >= 0; 0: "
                                                          "every {})",
                                                          key, value, lower));
                if (value == 0.0) continue;  // View3D's default: every row, every column
                (lower == "row" ? model_.view3d.row : model_.view3d.col) = static_cast<int>(value);
                (lower == "row" ? model_.view3d.row_line : model_.view3d.col_line) = number_;
            }
            if (lower == "maxd") {
                if (!(value > 0.0))
                    fail_at(source_, number_, fmt::format("control {}={} must be > 0 (the distance between surface "
                                                          "centroids beyond which a pair gets no factor)",
                                                          key, value));
                model_.view3d.max_distance = value;
                model_.view3d.max_distance_line = number_;
                model_.view3d.ignored.push_back(
                    fmt::format("{}={}: only `ffcube view3d` applies the cut-off distance; every pair is computed", key, value));
                continue;
            }
            if (lower == "eps") {
                // The same rule as --tolerance (validate(RowOptions)): a target double precision
                // can honour in a row's sum, below 1.
                if (!(value >= kMinTolerance && value < 1.0))
                    fail_at(source_, number_, fmt::format("control {}={} must be a number from {} to below 1 (the accuracy "
                                                          "target: ffcube's --tolerance)",
                                                          key, value, kMinTolerance));
                model_.view3d.eps = value;
                model_.view3d.eps_line = number_;
                continue;
            }
            static const std::map<std::string, std::string> kIgnored = {
                {"maxu", "ffcube's accuracy is set by --tolerance (eps)"},
                {"maxo", "ffcube's accuracy is set by --tolerance (eps)"},
                {"mino", "ffcube's accuracy is set by --tolerance (eps)"},
                {"maxv", "ffcube's accuracy is set by --tolerance (eps)"},
                {"row", "ffcube computes every row (read one row from the output)"},
                {"col", "ffcube computes every column (read one column from the output)"},
                {"list", "ffcube's log is set by --quiet"},
                {"prjd", "ffcube does not project"},
                {"prjreverse", "ffcube does not project"},
            };
            // The defaults change nothing, so they are honoured trivially; View3D's defaults:
            // eps 1e-4, maxU 12, maxO 8, minO 0, row 0, col 0 (above), list 0.
            static const std::map<std::string, double> kDefault = {{"list", 0.0}};
            if (const auto d = kDefault.find(lower); d != kDefault.end() && d->second == value) continue;
            const auto it = kIgnored.find(lower);
            const std::string setting = fmt::format("{}={}", it != kIgnored.end() ? key : detail::shown(key), value);
            const std::string why = it != kIgnored.end() ? it->second : "unknown control key";
            model_.view3d.ignored.push_back(fmt::format("{}: {}", setting, why));
            if (lower != "row" && lower != "col")  // warned about by the command (above)
                model_.warnings.push_back(fmt::format("{}:{}: control {} is ignored: {}", source_, number_, setting, why));
        }
    }

    void geometry_format(std::string_view line) {
        const std::string_view f = required(line, "the geometry format (F 3)");
        if (f != "3")
            fail_at(source_, number_, fmt::format("geometry format {} is not supported (only F 3: vertices, then surfaces)", shown(f)));
        saw_format_ = true;
    }

    void vertex(std::string_view line) {
        const long long n = integer(line, "vertex number");
        if (n != static_cast<long long>(model_.positions.size()) + 1)
            fail_at(source_, number_, fmt::format("vertex number {} is out of order (expected {}: vertices are numbered 1, 2, ... "
                                                  "in order)",
                                                  n, model_.positions.size() + 1));
        Vec3 p;
        for (int i = 0; i < 3; ++i) p[i] = detail::parse_number(required(line, "a vertex coordinate (V n x y z)"), source_, number_,
                                                                "a vertex coordinate");
        model_.positions.push_back(p);
    }

    // The O surfaces after every S surface (faces and objects: Scene::drawn's order), each as
    // two faces back to back, so that it blocks and intercepts from both sides (View3D's rule):
    // what a radiating surface sees of it, front or back, is measured and then left out, and so
    // never counts as sky.
    void append_obstructions() {
        const auto first_object = static_cast<std::uint32_t>(model_.objects.size());
        for (ObjFace& f : obstruction_faces_) {
            f.object += first_object;
            ObjFace back = f;
            std::reverse(back.v.begin(), back.v.end());
            model_.faces.push_back(std::move(f));
            model_.faces.push_back(std::move(back));
        }
        model_.objects.insert(model_.objects.end(), obstruction_objects_.begin(), obstruction_objects_.end());
        model_.obstruction_objects = static_cast<std::uint32_t>(obstruction_objects_.size());
    }

    std::vector<Vec3> polygon_of(const ObjFace& f) const {
        std::vector<Vec3> p;
        for (const std::uint32_t v : f.v) p.push_back(model_.positions[v]);
        return p;
    }

    std::uint32_t position_index(const Vec3& p) {
        const auto [it, inserted] = position_of_.try_emplace(std::array{p.x, p.y, p.z}, static_cast<std::uint32_t>(model_.positions.size()));
        if (inserted) model_.positions.push_back(p);
        return it->second;
    }

    // Every surface's faces, in surface order: a surface with subsurfaces (S, or null surfaces N,
    // whose base it is) keeps what they leave of it, as convex pieces (vs3_subsurfaces.hpp), each
    // a face of its object on its line; View3D subtracts the subsurfaces' factors from the base's
    // and their areas from its area, which is the view factor of that rest. An N surface's polygon
    // is an obstruction-only face (blocks, from both sides, what would have seen the covered part).
    void make_faces() {
        for (std::size_t i = 0; i < model_.positions.size(); ++i) {
            const Vec3& p = model_.positions[i];
            position_of_.try_emplace(std::array{p.x, p.y, p.z}, static_cast<std::uint32_t>(i));
        }
        std::vector<std::vector<std::size_t>> children(surfaces_.size());
        for (std::size_t n = 0; n < surfaces_.size(); ++n) {
            const Surface& s = surfaces_[n];
            if (s.base == 0) continue;
            const Surface& b = surfaces_[static_cast<std::size_t>(s.base - 1)];
            const std::string problem = detail::subsurface_problem(polygon_of(b.face), polygon_of(s.face), s.kind == 'S');
            if (!problem.empty())
                fail_at(source_, s.face.line,
                        fmt::format("{} {} cannot lie on its base surface {} (line {}): {}",
                                    s.kind == 'S' ? "subsurface" : std::string(kind_name(s.kind)) + " surface", n + 1, s.base,
                                    b.face.line, problem));
            children[static_cast<std::size_t>(s.base - 1)].push_back(n);
            if (s.kind == 'M')
                model_.view3d.masks.push_back(View3dControls::Mask{obstruction_objects_[s.face.object], b.face.object,
                                                                   s.s_objects_before, polygon_area(polygon_of(s.face)), s.emissivity});
        }
        for (std::size_t n = 0; n < surfaces_.size(); ++n)
            for (std::size_t i = 0; i < children[n].size(); ++i)
                for (std::size_t j = 0; j < i; ++j) {
                    const Surface& a = surfaces_[children[n][j]];
                    const Surface& b = surfaces_[children[n][i]];
                    const double overlap = detail::convex_overlap_area(polygon_of(a.face), polygon_of(b.face));
                    if (overlap > 1e-9 * polygon_area(polygon_of(surfaces_[n].face)))
                        fail_at(source_, b.face.line,
                                fmt::format("surface {} overlaps surface {} (line {}) on their base surface {} by {:.3g} (surfaces "
                                            "on one base must not overlap)",
                                            children[n][i] + 1, children[n][j] + 1, a.face.line, n + 1, overlap));
                }
        for (std::size_t n = 0; n < surfaces_.size(); ++n) {
            Surface& s = surfaces_[n];
            std::vector<ObjFace>& out = s.kind == 'S' ? model_.faces : obstruction_faces_;
            if (children[n].empty()) {
                out.push_back(s.face);
                continue;
            }
            std::vector<std::vector<Vec3>> holes;
            for (const std::size_t c : children[n]) holes.push_back(polygon_of(surfaces_[c].face));
            for (const std::vector<Vec3>& piece : detail::cut_holes(polygon_of(s.face), holes)) {
                ObjFace f = s.face;
                f.v.clear();
                for (const Vec3& p : piece) f.v.push_back(position_index(p));
                out.push_back(std::move(f));
            }
        }
    }

    static const char* kind_name(char kind) {
        return kind == 'O' ? "obstruction" : kind == 'N' ? "null" : kind == 'M' ? "masking" : "radiating";
    }

    // S (radiating), O (obstruction-only), M (masking) or N (null) surface: the same fields,
    // numbered in one sequence.
    void surface(std::string_view line, char kind) {
        const bool obstruction = kind != 'S';
        const long long n = integer(line, "surface number");
        if (n != static_cast<long long>(surfaces_.size()) + 1)
            fail_at(source_, number_, fmt::format("surface number {} is out of order (expected {}: surfaces are numbered 1, 2, "
                                                  "... in order)",
                                                  n, surfaces_.size() + 1));
        ObjFace face;
        face.line = number_;
        for (int i = 0; i < 4; ++i) {
            const long long v = integer(line, "vertex index (S n v1 v2 v3 v4 base cmb emit name)");
            if (v == 0 && i < 3) fail_at(source_, number_, fmt::format("vertex {} of the surface is 0 (only v4 may be 0, for a triangle)", i + 1));
            if (v != 0) face.v.push_back(static_cast<std::uint32_t>(v - 1));
        }
        for (std::size_t a = 0; a < face.v.size(); ++a)
            for (std::size_t b = a + 1; b < face.v.size(); ++b)
                if (face.v[a] == face.v[b])
                    fail_at(source_, number_, fmt::format("vertex {} appears twice in the surface", face.v[a] + 1));
        const long long base = integer(line, "base surface (S n v1 v2 v3 v4 base cmb emit name)");
        const long long cmb = integer(line, "combine surface (S n v1 v2 v3 v4 base cmb emit name)");
        const double emit = detail::parse_number(required(line, "the emissivity (S n v1 v2 v3 v4 base cmb emit name)"), source_,
                                                 number_, "the emissivity");
        const std::string_view name = required(line, "the surface name (S n v1 v2 v3 v4 base cmb emit name)");
        std::string_view extra;
        if (token(line, extra)) fail_at(source_, number_, fmt::format("unexpected {} after the surface name", shown(extra)));
        if (kind == 'O' && base != 0)
            fail_at(source_, number_, fmt::format("obstruction surface {} has base {}: an O surface cannot be a subsurface (it "
                                                  "has no row or column to subtract from its base; base must be 0)",
                                                  n, base));
        if (obstruction && cmb != 0)
            fail_at(source_, number_, fmt::format("{} surface {} has cmb {}: an {} surface cannot be combined (it has no row or "
                                                  "column; cmb must be 0)",
                                                  kind_name(kind), n, cmb, kind));
        if (kind != 'S' && kind != 'O' && base == 0)
            fail_at(source_, number_, fmt::format("{} surface {} has base 0: it covers part of its base, so it needs one (an "
                                                  "earlier S surface)",
                                                  kind_name(kind), n));
        if (base != 0) {
            if (base >= n)
                fail_at(source_, number_, fmt::format("base {} must name an earlier surface (this is surface {})", base, n));
            const char base_kind = surfaces_[static_cast<std::size_t>(base - 1)].kind;
            if (base_kind == 'N' || base_kind == 'M')
                fail_at(source_, number_, fmt::format("base {} is a {} surface ({}), which cannot have subsurfaces", base,
                                                      kind_name(base_kind), base_kind));
            if ((kind == 'N' || kind == 'M') && base_kind != 'S')
                fail_at(source_, number_, fmt::format("base {} of a {} surface must be a radiating surface (S), not an "
                                                      "obstruction (O)",
                                                      base, kind_name(kind)));
        }
        if (!(emit >= 0.0 && emit <= 1.0))
            fail_at(source_, number_, fmt::format("emissivity {} must be within [0,1]", emit));
        std::uint32_t object = 0;
        if (cmb != 0) {
            if (cmb >= n)
                fail_at(source_, number_, fmt::format("cmb {} must name an earlier surface (this is surface {})", cmb, n));
            const Surface& target = surfaces_[static_cast<std::size_t>(cmb - 1)];
            if (target.kind != 'S')
                fail_at(source_, number_, fmt::format("cmb {} names {} {} surface ({}), which has no row or column of its own to "
                                                      "combine with",
                                                      cmb, target.kind == 'O' ? "an" : "a", kind_name(target.kind), target.kind));
            if (target.cmb != 0)
                fail_at(source_, number_, fmt::format("cmb {} names a surface that is itself combined with surface {} (name the "
                                                      "lowest-numbered surface of the group: no chains)",
                                                      cmb, target.cmb));
            object = target.face.object;
        } else {
            const auto [it, inserted] = line_of_name_.try_emplace(std::string(name), number_);
            if (!inserted)
                fail_at(source_, number_, fmt::format("surface name {} is already used on line {} (names must be unique; combine "
                                                      "surfaces with cmb)",
                                                      shown(name), it->second));
            std::vector<std::string>& objects = obstruction ? obstruction_objects_ : model_.objects;
            object = static_cast<std::uint32_t>(objects.size());  // O: counted after the S objects (append_obstructions)
            objects.emplace_back(name);
        }
        face.object = object;
        face.material = material(emit);
        surfaces_.push_back(Surface{kind, base, cmb, std::move(face), static_cast<std::uint32_t>(model_.objects.size()), emit});
    }

    // An opaque grey surface of emissivity ε reflects ρ = 1 − ε (Kirchhoff), emits nothing itself.
    std::uint32_t material(double emissivity) {
        const auto [it, inserted] = material_of_emissivity_.try_emplace(emissivity, static_cast<std::uint32_t>(model_.materials.size()));
        if (inserted) model_.materials.push_back(Material{fmt::format("emissivity {}", emissivity), Vec3(1.0 - emissivity), Vec3(0.0)});
        return it->second;
    }

    detail::LineReader reader_;
    const std::string& source_;
    ObjModel model_;
    std::uint32_t number_ = 0;
    bool saw_format_ = false;
    struct Surface {
        char kind = 'S';  // S, O or N
        long long base = 0, cmb = 0;
        ObjFace face;  // as written (object, material, line)
        std::uint32_t s_objects_before = 0;  // S objects made before this line (a mask's View3D position)
        double emissivity = 0.0;
    };
    std::vector<Surface> surfaces_;  // every S, O and N line, in order
    std::map<std::array<double, 3>, std::uint32_t> position_of_;  // for the vertices subsurfaces add
    std::unordered_map<std::string, std::uint32_t> line_of_name_;  // surface name -> its line
    std::vector<ObjFace> obstruction_faces_;         // O surfaces, objects counted from 0
    std::vector<std::string> obstruction_objects_;
    std::map<double, std::uint32_t> material_of_emissivity_;
};

}  // namespace

ObjModel parse_vs3(std::string_view text, const std::string& source) { return Vs3Parser(text, source).run(); }

ObjModel load_vs3(const std::filesystem::path& path) {
    return parse_vs3(read_scene_file(path, "a View3D file"), path.string());
}

}  // namespace ffcube
