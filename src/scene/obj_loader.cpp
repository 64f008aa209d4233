// Hand-written OBJ/MTL reader. tinyobjloader was not used because it cannot report the line of a
// NaN, of an overflowing number or of a bad index, and every refusal here must name file and line.
// The whole file is read at once and parsed through string_views: no allocation per token, only
// per face (ObjFace owns its index vector).
#include "ffcube/scene/obj_loader.hpp"

#include "ffcube/scene/load_model.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cerrno>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <limits>
#include <unordered_map>

#include "ffcube/core/error.hpp"

namespace ffcube {
namespace {

// Longest token (or name) accepted. Real OBJ tokens are numbers, indices and names of a few dozen
// bytes; a longer one means the file is not OBJ text, and refusing it keeps messages short.
constexpr std::size_t kMaxToken = 4096;
// Every number must be finite and at most this in magnitude. Doubles still resolve 0.125 units at
// 1e15, and squares (areas, 1e30) and products stay far from overflow everywhere downstream.
constexpr double kMaxMagnitude = 1e15;
// Warnings about individual lines stop after this many; a summary line says how many more.
constexpr std::size_t kMaxLineWarnings = 10;

[[noreturn]] void fail(const std::string& source, std::uint32_t line, const std::string& rule) {
    throw InputError(fmt::format("{}:{}: {}", source, line, rule));
}

bool is_space(char c) { return c == ' ' || c == '\t' || c == '\r' || c == '\v' || c == '\f'; }

std::string_view trim(std::string_view s) {
    while (!s.empty() && is_space(s.front())) s.remove_prefix(1);
    while (!s.empty() && is_space(s.back())) s.remove_suffix(1);
    return s;
}

// Splits text into lines (LF or CRLF; a final line without newline counts), with the UTF-8 BOM
// and comments removed. A NUL byte anywhere means binary data, not OBJ/MTL text.
class LineReader {
public:
    LineReader(std::string_view text, const std::string& source, const char* kind) : rest_(text) {
        if (rest_.substr(0, 3) == "\xEF\xBB\xBF") rest_.remove_prefix(3);
        if (const void* nul = std::memchr(text.data(), '\0', text.size())) {
            const auto offset = static_cast<std::size_t>(static_cast<const char*>(nul) - text.data());
            const auto line = 1 + std::count(text.begin(), text.begin() + static_cast<std::ptrdiff_t>(offset), '\n');
            fail(source, static_cast<std::uint32_t>(line),
                 fmt::format("not an {} file (binary data: a NUL byte)", kind));
        }
    }

    // Next line with its comment stripped; false at the end of the text.
    bool next(std::string_view& line) {
        if (done_) return false;
        const std::size_t eol = rest_.find('\n');
        line = rest_.substr(0, eol);
        if (eol == std::string_view::npos) {
            done_ = true;
        } else {
            rest_.remove_prefix(eol + 1);
        }
        ++number_;
        if (const std::size_t hash = line.find('#'); hash != std::string_view::npos) line = line.substr(0, hash);
        return true;
    }

    std::uint32_t number() const { return number_; }

private:
    std::string_view rest_;
    std::uint32_t number_ = 0;
    bool done_ = false;
};

// Whitespace-separated tokens of one line; refuses a token longer than kMaxToken.
class Tokens {
public:
    Tokens(std::string_view line, const std::string& source, std::uint32_t number)
        : rest_(line), source_(source), number_(number) {}

    bool next(std::string_view& token) {
        while (!rest_.empty() && is_space(rest_.front())) rest_.remove_prefix(1);
        if (rest_.empty()) return false;
        std::size_t n = 0;
        while (n < rest_.size() && !is_space(rest_[n])) ++n;
        if (n > kMaxToken)
            fail(source_, number_, fmt::format("a token of {} bytes is longer than the limit of {} bytes "
                                               "(is this a text file in the right format?)",
                                               n, kMaxToken));
        token = rest_.substr(0, n);
        rest_.remove_prefix(n);
        return true;
    }

    // The rest of the line, trimmed: names ('o', 'usemtl', 'mtllib') may contain spaces.
    std::string_view rest_as_name() {
        const std::string_view name = trim(rest_);
        if (name.size() > kMaxToken)
            fail(source_, number_, fmt::format("a name of {} bytes is longer than the limit of {} bytes",
                                               name.size(), kMaxToken));
        rest_ = {};
        return name;
    }

private:
    std::string_view rest_;
    const std::string& source_;
    std::uint32_t number_;
};

std::string shown(std::string_view token) {
    constexpr std::size_t kShown = 40;
    if (token.size() <= kShown) return fmt::format("'{}'", token);
    return fmt::format("'{}...'", token.substr(0, kShown));
}

// A number as OBJ/MTL write them: decimal or scientific, an optional sign. Refuses anything else,
// NaN, infinities and magnitudes above kMaxMagnitude, each with its own rule in the message.
double parse_number(std::string_view token, const std::string& source, std::uint32_t line, const char* what) {
    std::string_view digits = token;
    if (digits.size() > 1 && digits.front() == '+') digits.remove_prefix(1);  // from_chars refuses '+'
    double value = 0.0;
    const auto [end, ec] = std::from_chars(digits.data(), digits.data() + digits.size(), value);
    if (end != digits.data() + digits.size() || (ec != std::errc() && ec != std::errc::result_out_of_range))
        fail(source, line, fmt::format("{} is not a number ({})", shown(token), what));
    if (ec == std::errc::result_out_of_range) {
        // Overflow or underflow: strtod tells which. Underflow to (almost) zero is harmless.
        const std::string copy(digits);
        value = std::strtod(copy.c_str(), nullptr);
        if (std::abs(value) <= 1.0) return value;
        fail(source, line, fmt::format("{} overflows a double ({}; numbers must be finite with magnitude at most 1e15)",
                                       shown(token), what));
    }
    if (!std::isfinite(value))
        fail(source, line, fmt::format("{} is not a finite number ({}; NaN and infinity are refused)", shown(token), what));
    if (std::abs(value) > kMaxMagnitude)
        fail(source, line, fmt::format("{} is too large ({}; numbers must have magnitude at most 1e15)", shown(token), what));
    return value;
}

// Whether an unknown keyword looks like binary data rather than an OBJ statement we do not use.
bool has_control_bytes(std::string_view token) {
    return std::any_of(token.begin(), token.end(), [](char c) {
        const auto u = static_cast<unsigned char>(c);
        return u < 0x20 || u == 0x7F;
    });
}

// Statements that are valid OBJ but carry nothing ffcube uses (texture coordinates, normals,
// smoothing groups, lines, points, free-form geometry, display attributes).
bool is_ignored_obj_keyword(std::string_view k) {
    static constexpr std::string_view kIgnored[] = {
        "vt", "vn", "vp", "s", "l", "p", "mg", "lod", "maplib", "usemap", "bevel", "c_interp", "d_interp",
        "shadow_obj", "trace_obj", "cstype", "deg", "bmat", "step", "curv", "curv2", "surf", "parm",
        "trim", "hole", "scrv", "sp", "end", "con", "call", "csh"};
    return std::find(std::begin(kIgnored), std::end(kIgnored), k) != std::end(kIgnored);
}

// Interns names in order of first appearance.
class NameTable {
public:
    std::uint32_t intern(std::string_view name) {
        const auto [it, inserted] = index_.try_emplace(std::string(name), static_cast<std::uint32_t>(names_.size()));
        if (inserted) names_.emplace_back(name);
        return it->second;
    }
    const std::vector<std::string>& names() const { return names_; }
    bool empty() const { return names_.empty(); }

private:
    std::unordered_map<std::string, std::uint32_t> index_;
    std::vector<std::string> names_;
};

// The MTL source name used in messages: the library's path next to the OBJ.
std::string mtl_source(const std::string& obj_source, std::string_view name) {
    const std::filesystem::path dir = std::filesystem::path(obj_source).parent_path();
    return dir.empty() ? std::string(name) : (dir / std::string(name)).string();
}

constexpr std::uint32_t kNone = std::numeric_limits<std::uint32_t>::max();

class ObjParser {
public:
    ObjParser(std::string_view text, const std::string& source, const MtlResolver& mtl, const ObjLoadOptions& options)
        : text_(text), mtl_(mtl), options_(options) {
        model_.source = source;
        model_.materials.push_back(Material{"default", Vec3(0.5), Vec3(0.0)});
    }

    ObjModel run() {
        LineReader reader(text_, model_.source, "OBJ");
        std::string_view line;
        while (reader.next(line)) statement(line, reader.number());
        if (model_.faces.empty()) {
            std::string hint;
            if (unknown_count_ > 0)
                hint = fmt::format(" ({} lines with unknown keywords: is this an OBJ file?)", unknown_count_);
            throw InputError(fmt::format("{}: no faces: the scene has no geometry{}", model_.source, hint));
        }
        check_indices();
        assign_objects();
        assign_materials();
        if (unknown_count_ > 0)
            model_.warnings.push_back(fmt::format("{}: ignored {} statements with unknown keywords (the first, {}, on line {})",
                                                  model_.source, unknown_count_, shown(first_unknown_), first_unknown_line_));
        return std::move(model_);
    }

private:
    void statement(std::string_view line, std::uint32_t number) {
        Tokens tokens(line, model_.source, number);
        std::string_view keyword;
        if (!tokens.next(keyword)) return;
        if (keyword == "v") {
            vertex(tokens, number);
        } else if (keyword == "f") {
            face(tokens, number);
        } else if (keyword == "o") {
            saw_o_ = true;
            current_o_ = o_names_.intern(name_or_default(tokens.rest_as_name()));
        } else if (keyword == "g") {
            current_g_ = g_names_.intern(name_or_default(tokens.rest_as_name()));
        } else if (keyword == "usemtl") {
            const std::string_view name = tokens.rest_as_name();
            current_mtl_ = usemtl_names_.intern(name);
            if (current_mtl_ == usemtl_lines_.size()) usemtl_lines_.push_back(number);
        } else if (keyword == "mtllib") {
            mtllib(tokens.rest_as_name(), number);
        } else if (!is_ignored_obj_keyword(keyword)) {
            if (has_control_bytes(keyword))
                fail(model_.source, number, "not an OBJ file (control bytes where a keyword should be)");
            if (unknown_count_++ == 0) {
                first_unknown_ = std::string(keyword.substr(0, 40));
                first_unknown_line_ = number;
            }
        }
    }

    static std::string_view name_or_default(std::string_view name) { return name.empty() ? "default" : name; }

    void vertex(Tokens& tokens, std::uint32_t number) {
        double xyz[3];
        std::string_view token;
        for (int i = 0; i < 3; ++i) {
            if (!tokens.next(token))
                fail(model_.source, number, fmt::format("'v' needs 3 coordinates, found {}", i));
            xyz[i] = parse_number(token, model_.source, number, "a vertex coordinate");
        }
        // A 4th value (w) or vertex colours may follow; ffcube uses neither.
        model_.positions.emplace_back(xyz[0], xyz[1], xyz[2]);
    }

    void face(Tokens& tokens, std::uint32_t number) {
        ObjFace f;
        f.line = number;
        std::string_view token;
        while (tokens.next(token)) f.v.push_back(face_index(token, number));
        if (f.v.size() < 3)
            fail(model_.source, number, fmt::format("a face needs at least 3 vertices, this one has {}", f.v.size()));
        model_.faces.push_back(std::move(f));
        face_o_.push_back(current_o_);
        face_g_.push_back(current_g_);
        face_mtl_.push_back(current_mtl_);
    }

    // The position index of "v", "v/vt", "v//vn" or "v/vt/vn", 0-based. Positive indices are
    // checked against the final vertex count in check_indices(); negative ones count back from
    // the vertices defined so far, as the OBJ format defines them.
    std::uint32_t face_index(std::string_view token, std::uint32_t number) {
        const std::string_view v = token.substr(0, token.find('/'));
        long long index = 0;
        const auto [end, ec] = std::from_chars(v.data(), v.data() + v.size(), index);
        if (v.empty() || end != v.data() + v.size() || (ec != std::errc() && ec != std::errc::result_out_of_range))
            fail(model_.source, number, fmt::format("face vertex {} is not an index (expected v, v/vt, v//vn or v/vt/vn)", shown(token)));
        const long long defined = static_cast<long long>(model_.positions.size());
        if (ec == std::errc::result_out_of_range)
            fail(model_.source, number, fmt::format("face index {} is out of range (the file defines {} vertices so far)", shown(v), defined));
        if (index == 0) fail(model_.source, number, "face index 0 is invalid (OBJ indices start at 1)");
        if (index < 0) {
            if (-index > defined)
                fail(model_.source, number,
                     fmt::format("face index {} is out of range (a negative index counts back from the {} vertices defined before this line)",
                                 index, defined));
            return static_cast<std::uint32_t>(defined + index);
        }
        if (index > static_cast<long long>(std::numeric_limits<std::uint32_t>::max()))
            fail(model_.source, number, fmt::format("face index {} is out of range (the file defines {} vertices so far)", index, defined));
        return static_cast<std::uint32_t>(index - 1);
    }

    void check_indices() const {
        const std::size_t n = model_.positions.size();
        for (const ObjFace& f : model_.faces)
            for (const std::uint32_t i : f.v)
                if (i >= n)
                    fail(model_.source, f.line,
                         fmt::format("face index {} is out of range (the file defines {} vertices)", std::uint64_t{i} + 1, n));
    }

    // 'mtllib' may name several files separated by spaces, or one file whose name has spaces:
    // the whole rest of the line is tried first, then its tokens.
    void mtllib(std::string_view rest, std::uint32_t number) {
        if (rest.empty()) fail(model_.source, number, "'mtllib' needs a file name");
        if (load_mtl(rest)) return;
        std::vector<std::string_view> names;
        Tokens tokens(rest, model_.source, number);
        std::string_view token;
        while (tokens.next(token)) names.push_back(token);
        // Every word is tried (no short cut at the first one missing), so the warning below can
        // name each path tried.
        const bool all_found = names.size() > 1 && std::count_if(names.begin(), names.end(), [this](std::string_view n) {
                                   return static_cast<bool>(mtl_(std::string(n)));
                               }) == static_cast<std::ptrdiff_t>(names.size());
        if (all_found) {
            for (const std::string_view n : names) load_mtl(n);
            return;
        }
        // Name every path tried (the whole rest of the line, then each word when there are
        // several), as the resolver saw them: relative to the OBJ's directory.
        std::string tried = fmt::format("'{}'", mtl_source(model_.source, rest));
        if (names.size() > 1)
            for (const std::string_view n : names) tried += fmt::format(", '{}'", mtl_source(model_.source, n));
        model_.warnings.push_back(fmt::format("{}:{}: material library '{}' not found (tried {}); its materials get the "
                                              "default (Kd 0.5 0.5 0.5, Ke 0 0 0)",
                                              model_.source, number, rest, tried));
    }

    bool load_mtl(std::string_view name) {
        const std::optional<std::string> text = mtl_(std::string(name));
        if (!text) return false;
        parse_mtl(*text, mtl_source(model_.source, name), model_.materials);
        return true;
    }

    // Objects by options_.objects_by; auto: 'o' names objects, a file without any 'o' is named by
    // its 'g' groups, a file with neither by its materials ('usemtl' names). Faces before the
    // first statement of the chosen kind belong to "default".
    void assign_objects() {
        ObjObjectsBy by = options_.objects_by;
        if (by == ObjObjectsBy::automatic)
            by = saw_o_ ? ObjObjectsBy::o : !g_names_.empty() ? ObjObjectsBy::g : ObjObjectsBy::material;
        const NameTable& table = by == ObjObjectsBy::o ? o_names_ : by == ObjObjectsBy::g ? g_names_ : usemtl_names_;
        const std::vector<std::uint32_t>& slots = by == ObjObjectsBy::o ? face_o_ : by == ObjObjectsBy::g ? face_g_ : face_mtl_;
        std::vector<std::uint32_t> object_of_slot(table.names().size(), kNone);
        std::uint32_t default_object = kNone;
        for (std::size_t i = 0; i < model_.faces.size(); ++i) {
            const std::uint32_t slot = slots[i];
            std::uint32_t& object = slot == kNone ? default_object : object_of_slot[slot];
            if (object == kNone) {
                object = static_cast<std::uint32_t>(model_.objects.size());
                // 'usemtl' with an empty name is allowed; as an object it is "default" like 'o'.
                model_.objects.push_back(slot == kNone ? std::string("default")
                                                       : std::string(name_or_default(table.names()[slot])));
            }
            model_.faces[i].object = object;
        }
    }

    void assign_materials() {
        std::unordered_map<std::string_view, std::uint32_t> by_name;
        // A later definition of the same name wins, as a later 'newmtl' overrides in most readers.
        for (std::size_t m = 1; m < model_.materials.size(); ++m)
            by_name[model_.materials[m].name] = static_cast<std::uint32_t>(m);
        std::vector<std::uint32_t> material_of_slot(usemtl_names_.names().size(), 0);
        std::size_t unknown = 0;
        for (std::size_t s = 0; s < material_of_slot.size(); ++s) {
            const std::string& name = usemtl_names_.names()[s];
            if (const auto it = by_name.find(name); it != by_name.end()) {
                material_of_slot[s] = it->second;
            } else if (unknown++ < kMaxLineWarnings) {
                model_.warnings.push_back(fmt::format("{}:{}: material '{}' is not defined in any material library; "
                                                      "its faces get the default (Kd 0.5 0.5 0.5, Ke 0 0 0)",
                                                      model_.source, usemtl_lines_[s], name));
            }
        }
        if (unknown > kMaxLineWarnings)
            model_.warnings.push_back(fmt::format("{}: {} more undefined materials get the default",
                                                  model_.source, unknown - kMaxLineWarnings));
        for (std::size_t i = 0; i < model_.faces.size(); ++i)
            model_.faces[i].material = face_mtl_[i] == kNone ? 0 : material_of_slot[face_mtl_[i]];
    }

    std::string_view text_;
    const MtlResolver& mtl_;
    ObjLoadOptions options_;
    ObjModel model_;

    NameTable o_names_, g_names_, usemtl_names_;
    std::vector<std::uint32_t> usemtl_lines_;  // line of the first 'usemtl' of each name
    bool saw_o_ = false;
    std::uint32_t current_o_ = kNone, current_g_ = kNone, current_mtl_ = kNone;
    // Per face, parallel to model_.faces until the names are resolved at the end.
    std::vector<std::uint32_t> face_o_, face_g_, face_mtl_;

    std::size_t unknown_count_ = 0;
    std::string first_unknown_;
    std::uint32_t first_unknown_line_ = 0;
};

// Reads "Kd r [g b]" or "Ke r [g b]": one value means grey.
Vec3 parse_colour(Tokens& tokens, std::string_view keyword, const std::string& source, std::uint32_t line) {
    std::string_view token[3];
    int n = 0;
    std::string_view extra;
    while (n < 3 && tokens.next(token[n])) ++n;
    if (n == 0 || n == 2 || tokens.next(extra))
        fail(source, line, fmt::format("'{}' takes 1 or 3 numbers (r g b, or one grey value)", keyword));
    if (token[0] == "spectral" || token[0] == "xyz")
        fail(source, line, fmt::format("'{} {}' is not supported: give r g b", keyword, token[0]));
    Vec3 c;
    for (int i = 0; i < 3; ++i) {
        const std::string_view t = token[n == 1 ? 0 : i];
        const double value = parse_number(t, source, line,
                                          keyword == "Kd" ? "Kd: diffuse reflectance within [0,1]" : "Ke: emitted radiosity >= 0");
        if (keyword == "Kd" && !(value >= 0.0 && value <= 1.0))
            fail(source, line, fmt::format("Kd {} must be within [0,1] (diffuse reflectance per channel; above 1 "
                                           "a surface would reflect more energy than it receives)",
                                           shown(t)));
        if (keyword == "Ke" && !(value >= 0.0))
            fail(source, line, fmt::format("Ke {} must be >= 0 (emitted radiosity per channel)", shown(t)));
        c[i] = value;
    }
    return c;
}

}  // namespace

void parse_mtl(std::string_view text, const std::string& source, std::vector<Material>& out) {
    LineReader reader(text, source, "MTL");
    std::string_view line;
    std::optional<std::size_t> current;  // index in 'out' of the material being defined
    while (reader.next(line)) {
        const std::uint32_t number = reader.number();
        Tokens tokens(line, source, number);
        std::string_view keyword;
        if (!tokens.next(keyword)) continue;
        if (keyword == "newmtl") {
            const std::string_view name = tokens.rest_as_name();
            if (name.empty()) fail(source, number, "'newmtl' needs a material name");
            out.push_back(Material{std::string(name), Vec3(0.5), Vec3(0.0)});
            current = out.size() - 1;
        } else if (keyword == "Kd" || keyword == "Ke") {
            if (!current)
                fail(source, number, fmt::format("'{}' before any 'newmtl' (which material does it belong to?)", keyword));
            (keyword == "Kd" ? out[*current].kd : out[*current].ke) = parse_colour(tokens, keyword, source, number);
        } else if (has_control_bytes(keyword)) {
            fail(source, number, "not an MTL file (control bytes where a keyword should be)");
        }
        // Other statements (Ka, Ks, Ns, d, illum, maps) carry nothing a diffuse radiosity uses.
    }
}

ObjObjectsBy parse_objects_by(std::string_view name, std::string_view option) {
    if (name == "auto") return ObjObjectsBy::automatic;
    if (name == "o") return ObjObjectsBy::o;
    if (name == "g") return ObjObjectsBy::g;
    if (name == "material") return ObjObjectsBy::material;
    throw InputError(fmt::format("{} {}: must be auto, o, g or material", option, shown(name)));
}

ObjModel parse_obj(std::string_view text, const std::string& source, const MtlResolver& mtl, const ObjLoadOptions& options) {
    return ObjParser(text, source, mtl, options).run();
}

namespace {

// Reads a whole file; nullopt when it does not exist or is not a regular file. Throws InputError
// when it exists but cannot be read.
std::optional<std::string> read_file(const std::filesystem::path& path) {
    std::error_code ec;
    if (!std::filesystem::is_regular_file(path, ec)) return std::nullopt;
    return read_scene_file(path, "a scene file");
}

// A material library must lie inside the OBJ's folder (docs/robustness.md, "Input paths": no file
// outside the model is read): an absolute path, or one that leaves the folder ('..', or a symlink
// pointing out; compared after weakly_canonical), is refused naming the OBJ and the library.
std::filesystem::path inside_model_folder(const std::filesystem::path& dir, const std::string& name,
                                          const std::string& source) {
    namespace fs = std::filesystem;
    const fs::path rel(name);
    if (rel.is_absolute())
        throw InputError(fmt::format("{}: mtllib '{}': an absolute path; only material libraries inside the model's "
                                     "folder are read",
                                     source, name));
    std::error_code ec;
    const fs::path base = fs::weakly_canonical(dir.empty() ? fs::path(".") : dir, ec);
    const fs::path full = ec ? fs::path() : fs::weakly_canonical(base / rel, ec);
    const auto [b, f] = std::mismatch(base.begin(), base.end(), full.begin(), full.end());
    if (ec || b != base.end() || f == full.end())
        throw InputError(fmt::format("{}: mtllib '{}' resolves to {}, outside the model's folder {} (only files "
                                     "inside it are read)",
                                     source, name, full.string(), base.string()));
    return dir / rel;
}

}  // namespace

ObjModel load_obj(const std::filesystem::path& path, const ObjLoadOptions& options) {
    const std::string text = read_scene_file(path, "an OBJ file");
    const std::filesystem::path dir = path.parent_path();
    const MtlResolver resolver = [&dir, &path](const std::string& name) {
        return read_file(inside_model_folder(dir, name, path.string()));
    };
    return parse_obj(text, path.string(), resolver, options);
}

}  // namespace ffcube
