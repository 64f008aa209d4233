// STL, ASCII and binary, by hand: the format is a list of triangles, and a hand-written reader
// can name the line or facet of every refusal and read binary files exactly (float32 → double).
#include "ffcube/scene/stl_loader.hpp"

#include <fmt/format.h>
#include <glm/geometric.hpp>

#include <algorithm>
#include <array>
#include <bit>
#include <cctype>
#include <cstring>
#include <limits>
#include <unordered_map>

#include "ffcube/core/error.hpp"
#include "ffcube/scene/load_model.hpp"
#include "text_lines.hpp"

namespace ffcube {
namespace {

using detail::fail_at;
using detail::kMaxToken;
using detail::shown;

static_assert(std::endian::native == std::endian::little, "binary STL is read as little-endian");

constexpr std::size_t kHeader = 84;    // 80 bytes of header, uint32 facet count
constexpr std::size_t kFacet = 50;     // 12 float32 (normal, 3 vertices) and a uint16 attribute
// The mesher's degeneracy bound (mesher.cpp): area at most 1e-12 × (longest edge)².
constexpr double kDegenerate = 1e-12;

struct PositionKey {
    double x, y, z;
    bool operator==(const PositionKey&) const = default;
};
struct PositionHash {
    std::size_t operator()(const PositionKey& k) const {
        std::uint64_t h = 1469598103934665603ull;
        for (const double d : {k.x, k.y, k.z}) h = (h ^ std::bit_cast<std::uint64_t>(d)) * 1099511628211ull;
        return static_cast<std::size_t>(h ^ (h >> 29));
    }
};

// Collects facets into an ObjModel: merges exactly coinciding vertices, drops degenerate facets.
class Builder {
public:
    explicit Builder(const std::string& source) {
        model_.source = source;
        model_.materials.push_back(Material{"default", Vec3(0.5), Vec3(0.0)});
    }

    std::uint32_t object(const std::string& name) {
        const auto it = std::find(model_.objects.begin(), model_.objects.end(), name);
        if (it != model_.objects.end()) return static_cast<std::uint32_t>(it - model_.objects.begin());
        model_.objects.push_back(name);
        return static_cast<std::uint32_t>(model_.objects.size() - 1);
    }

    // 'where' is the line (ASCII) or the 1-based facet number (binary).
    void facet(const std::array<Vec3, 3>& p, const Vec3& stored_normal, std::uint32_t object, std::uint32_t where) {
        std::array<std::uint32_t, 3> v{};
        for (int i = 0; i < 3; ++i) v[i] = vertex(p[i]);
        const bool repeated = v[0] == v[1] || v[1] == v[2] || v[0] == v[2];
        const double size = polygon_max_edge(p);
        const double area = repeated ? 0.0 : polygon_area(p);
        if (repeated || !(area > kDegenerate * size * size)) {
            if (model_.dropped_degenerate++ == 0) first_degenerate_ = where;
            return;
        }
        // The winding decides the front; a stored normal pointing the other way is ignored.
        const Vec3 n = glm::cross(p[1] - p[0], p[2] - p[0]);
        if (glm::dot(n, stored_normal) < 0.0 && disagreeing_++ == 0) first_disagreeing_ = where;
        model_.faces.push_back(ObjFace{{v[0], v[1], v[2]}, object, 0, where});
    }

    ObjModel finish(const char* where_word) {
        if (model_.dropped_degenerate > 0)
            model_.warnings.push_back(fmt::format("{}: dropped {} degenerate facets (a repeated vertex or no area; the first at "
                                                  "{} {})",
                                                  model_.source, model_.dropped_degenerate, where_word, first_degenerate_));
        if (disagreeing_ > 0)
            model_.warnings.push_back(fmt::format("{}: {} facets have a stored normal opposite to their vertex order (the first "
                                                  "at {} {}); the vertex order (counter-clockwise seen from the front) was used",
                                                  model_.source, disagreeing_, where_word, first_disagreeing_));
        if (model_.faces.empty()) {
            if (model_.dropped_degenerate > 0)
                throw InputError(fmt::format("{}: no faces with non-zero area (all {} facets are degenerate)", model_.source,
                                             model_.dropped_degenerate));
            throw InputError(fmt::format("{}: no facets: the scene has no geometry", model_.source));
        }
        return std::move(model_);
    }

private:
    std::uint32_t vertex(const Vec3& p) {
        const PositionKey key{p.x + 0.0, p.y + 0.0, p.z + 0.0};  // -0 and +0 coincide
        const auto [it, inserted] = index_.try_emplace(key, static_cast<std::uint32_t>(model_.positions.size()));
        if (inserted) {
            if (model_.positions.size() >= std::numeric_limits<std::uint32_t>::max() - 1)
                throw InputError(fmt::format("{}: more than 2^32 vertices", model_.source));
            model_.positions.push_back(p);
        } else {
            ++model_.merged_vertices;
        }
        return it->second;
    }

    ObjModel model_;
    std::unordered_map<PositionKey, std::uint32_t, PositionHash> index_;
    std::uint32_t first_degenerate_ = 0;
    std::size_t disagreeing_ = 0;
    std::uint32_t first_disagreeing_ = 0;
};

std::uint32_t read_u32(const char* p) {
    std::uint32_t v;
    std::memcpy(&v, p, 4);
    return v;
}

float read_f32(const char* p) {
    float v;
    std::memcpy(&v, p, 4);
    return v;
}

ObjModel parse_binary(std::string_view bytes, const std::string& source, const std::string& stem) {
    const std::uint64_t n = read_u32(bytes.data() + 80);
    Builder builder(source);
    const std::uint32_t object = builder.object(stem);
    for (std::uint64_t f = 0; f < n; ++f) {
        const char* rec = bytes.data() + kHeader + f * kFacet;
        const auto number = static_cast<std::uint32_t>(f + 1);
        float values[12];
        for (int i = 0; i < 12; ++i) {
            values[i] = read_f32(rec + 4 * i);
            if (!std::isfinite(values[i]) && i >= 3)
                throw InputError(fmt::format("{}: facet {} of {}: vertex {} has a coordinate that is not a finite number ({}); "
                                             "NaN and infinity are refused",
                                             source, number, n, i / 3, values[i]));
            if (std::abs(values[i]) > detail::kMaxCoordinate && i >= 3)
                throw InputError(fmt::format("{}: facet {} of {}: vertex {} has a coordinate {} of magnitude above 1e15",
                                             source, number, n, i / 3, values[i]));
        }
        // A stored normal that is NaN is only ignored (the winding decides).
        Vec3 normal(values[0], values[1], values[2]);
        if (!std::isfinite(normal.x) || !std::isfinite(normal.y) || !std::isfinite(normal.z)) normal = Vec3(0.0);
        const std::array<Vec3, 3> p = {Vec3(values[3], values[4], values[5]), Vec3(values[6], values[7], values[8]),
                                       Vec3(values[9], values[10], values[11])};
        builder.facet(p, normal, object, number);
    }
    ObjModel model = builder.finish("facet");
    model.faces_numbered = true;
    return model;
}

bool iequals(std::string_view a, std::string_view b) {
    return a.size() == b.size() && std::equal(a.begin(), a.end(), b.begin(), [](char x, char y) {
               return std::tolower(static_cast<unsigned char>(x)) == std::tolower(static_cast<unsigned char>(y));
           });
}

class AsciiParser {
public:
    AsciiParser(std::string_view text, const std::string& source, const std::string& stem)
        : reader_(text, source, {},
                  "not an ASCII STL file (control bytes; a binary STL must be exactly 84 + 50 x (facet count) bytes long)"),
          source_(source), stem_(stem), builder_(source) {}

    ObjModel run() {
        enum class State { Outside, Solid, Facet, Loop, EndLoop };
        State state = State::Outside;
        std::uint32_t object = 0, solid_line = 0, facet_line = 0;
        std::array<Vec3, 3> p{};
        Vec3 normal(0.0);
        int vertices = 0;
        std::string_view line;
        while (next_line(line)) {
            std::string_view keyword;
            if (!token(line, keyword)) continue;
            const auto expect = [&](const char* what) {
                fail_at(source_, number_, fmt::format("expected {}, found {}", what, shown(keyword)));
            };
            switch (state) {
            case State::Outside:
                if (!iequals(keyword, "solid")) expect("'solid' (an ASCII STL file is a list of solids)");
                {
                    std::string name(trim(line));
                    if (name.size() > kMaxToken) fail_at(source_, number_, "a solid's name is longer than 4096 bytes");
                    object = builder_.object(name.empty() ? stem_ : name);
                }
                solid_line = number_;
                state = State::Solid;
                break;
            case State::Solid:
                if (iequals(keyword, "endsolid")) {
                    state = State::Outside;
                    ++solids_;
                    break;
                }
                if (!iequals(keyword, "facet")) expect("'facet' or 'endsolid'");
                {
                    std::string_view word;
                    if (!token(line, word) || !iequals(word, "normal")) fail_at(source_, number_, "expected 'facet normal nx ny nz'");
                    for (int i = 0; i < 3; ++i) normal[i] = number(line, "a facet normal");
                    no_more(line, "'facet normal' takes 3 numbers");
                }
                facet_line = number_;
                state = State::Facet;
                break;
            case State::Facet: {
                std::string_view word;
                if (!iequals(keyword, "outer") || !token(line, word) || !iequals(word, "loop")) expect("'outer loop'");
                no_more(line, "'outer loop' takes nothing after it");
                vertices = 0;
                state = State::Loop;
                break;
            }
            case State::Loop:
                if (iequals(keyword, "endloop")) {
                    if (vertices != 3)
                        fail_at(source_, number_,
                                fmt::format("a facet needs exactly 3 vertices, the one begun on line {} has {}", facet_line, vertices));
                    state = State::EndLoop;
                    break;
                }
                if (!iequals(keyword, "vertex")) expect("'vertex' or 'endloop'");
                if (vertices == 3)
                    fail_at(source_, number_, fmt::format("a facet needs exactly 3 vertices, the one begun on line {} has more",
                                                          facet_line));
                for (int i = 0; i < 3; ++i) p[vertices][i] = number(line, "a vertex coordinate");
                no_more(line, "'vertex' takes 3 numbers");
                ++vertices;
                break;
            case State::EndLoop:
                if (!iequals(keyword, "endfacet")) expect("'endfacet'");
                builder_.facet(p, normal, object, facet_line);
                state = State::Solid;
                break;
            }
        }
        if (state == State::Solid)
            throw InputError(fmt::format("{}:{}: the file ends inside the solid begun on line {} (no 'endsolid': truncated?)",
                                         source_, number_, solid_line));
        if (state != State::Outside)
            throw InputError(fmt::format("{}:{}: the file ends inside the facet begun on line {} (truncated?)", source_,
                                         number_, facet_line));
        if (solids_ == 0) throw InputError(fmt::format("{}: no solid: the scene has no geometry", source_));
        return builder_.finish("line");
    }

private:
    bool next_line(std::string_view& line) {
        const bool more = reader_.next(line);
        number_ = reader_.line_number();
        return more;
    }
    bool token(std::string_view& line, std::string_view& out) const { return reader_.token(line, out); }
    double number(std::string_view& line, const char* what) const { return reader_.number(line, what); }
    void no_more(std::string_view& line, const char* rule) const { reader_.no_more(line, rule); }
    static std::string_view trim(std::string_view s) { return detail::LineReader::trim(s); }

    detail::LineReader reader_;
    const std::string& source_;
    const std::string& stem_;
    Builder builder_;
    std::uint32_t number_ = 0;
    std::size_t solids_ = 0;
};

bool begins_with_solid(std::string_view bytes) {
    if (bytes.substr(0, 3) == "\xEF\xBB\xBF") bytes.remove_prefix(3);
    while (!bytes.empty() && (detail::is_blank(bytes.front()) || bytes.front() == '\n')) bytes.remove_prefix(1);
    return bytes.size() >= 5 && iequals(bytes.substr(0, 5), "solid") && (bytes.size() == 5 || detail::is_blank(bytes[5]) || bytes[5] == '\n');
}

}  // namespace

bool is_binary_stl(std::string_view bytes) {
    if (bytes.size() < kHeader) return false;
    const std::uint64_t n = read_u32(bytes.data() + 80);
    return bytes.size() == kHeader + kFacet * n;
}

ObjModel parse_stl(std::string_view bytes, const std::string& source, const std::string& stem) {
    if (is_binary_stl(bytes)) return parse_binary(bytes, source, stem);
    if (begins_with_solid(bytes)) return AsciiParser(bytes, source, stem).run();
    if (bytes.size() < kHeader)
        throw InputError(fmt::format("{}: not an STL file: it does not begin with 'solid' (ASCII) and is {} bytes, shorter "
                                     "than a binary STL's 84-byte header",
                                     source, bytes.size()));
    const std::uint64_t n = read_u32(bytes.data() + 80);
    const std::uint64_t expected = kHeader + kFacet * n;
    if (bytes.size() < expected)
        throw InputError(fmt::format("{}: binary STL cut short (or not an STL file): the header says {} facets ({} bytes), the "
                                     "file has {} bytes; facet {} is incomplete or missing (truncated?)",
                                     source, n, expected, bytes.size(), (bytes.size() - kHeader) / kFacet + 1));
    throw InputError(fmt::format("{}: not an STL file: the header says {} facets ({} bytes) but the file has {} bytes, {} "
                                 "more than that, and it does not begin with 'solid' (ASCII)",
                                 source, n, expected, bytes.size(), bytes.size() - expected));
}

ObjModel load_stl(const std::filesystem::path& path) {
    const std::string bytes = read_scene_file(path, "an STL file");
    return parse_stl(bytes, path.string(), path.stem().string());
}

}  // namespace ffcube
