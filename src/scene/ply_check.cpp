// PLY pre-check (import_checks.hpp). Why each rule: Debian's assimp 5.2.5
//  - loops forever when no line is exactly `end_header` (it searches for the word and then for
//    the end of its line; `end_headerX` or `end_header` in a comment never end the search);
//  - crashes when `end_header` is glued to the binary data or misspelt (`end_headers`);
//  - reserves `count × sizeof(record)` before reading, so a 300-byte file declaring 300 M
//    list entries takes gigabytes;
//  - pads a face element shorter than declared with copies, and reads face lines as vertices
//    when the vertex count is too large: silently wrong geometry.
// So the header is parsed here strictly, and the data is walked record by record (each record
// costs at least one byte or one line, so the walk is linear in the file) before assimp runs.
#include <fmt/format.h>

#include <array>
#include <charconv>
#include <cstdint>
#include <cstring>
#include <limits>
#include <string>
#include <string_view>
#include <vector>

#include "ffcube/core/error.hpp"
#include "ffcube/scene/import_checks.hpp"

namespace ffcube {
namespace {

// A header longer than this is not a mesh's header (real ones are under 1 KiB; comments and
// obj_info lines included, a few KiB).
constexpr std::size_t kMaxHeaderBytes = std::size_t(1) << 20;

enum class Encoding { ascii, little, big };

struct Type {
    std::uint8_t size = 0;  // 0: not a type
    bool integer = false;
    bool is_signed = false;
};

Type type_of(std::string_view t) {
    static const std::array<std::pair<std::string_view, Type>, 16> types{{
        {"char", {1, true, true}},     {"int8", {1, true, true}},      {"uchar", {1, true, false}},
        {"uint8", {1, true, false}},   {"short", {2, true, true}},     {"int16", {2, true, true}},
        {"ushort", {2, true, false}},  {"uint16", {2, true, false}},   {"int", {4, true, true}},
        {"int32", {4, true, true}},    {"uint", {4, true, false}},     {"uint32", {4, true, false}},
        {"float", {4, false, true}},   {"float32", {4, false, true}},  {"double", {8, false, true}},
        {"float64", {8, false, true}},
    }};
    for (const auto& [name, type] : types)
        if (name == t) return type;
    return {};
}

struct Property {
    std::string name;
    bool list = false;
    Type count;  // lists: the count's type
    Type value;  // the value's (a list's entries')
};

struct Element {
    std::string name;
    std::uint64_t count = 0;
    std::size_t line = 0;  // header line, for messages
    std::vector<Property> properties;
};

// A line of the file as it may be printed in a message: at most 40 characters, non-printable
// bytes as \xNN.
std::string shown(std::string_view line) {
    std::string out;
    for (std::size_t i = 0; i < line.size() && i < 40; ++i) {
        const auto c = static_cast<unsigned char>(line[i]);
        if (c >= 0x20 && c < 0x7f) out += static_cast<char>(c);
        else out += fmt::format("\\x{:02x}", c);
    }
    if (line.size() > 40) out += "...";
    return out;
}

std::vector<std::string_view> words(std::string_view line) {
    std::vector<std::string_view> out;
    std::size_t i = 0;
    while (i < line.size()) {
        while (i < line.size() && (line[i] == ' ' || line[i] == '\t')) ++i;
        const std::size_t start = i;
        while (i < line.size() && line[i] != ' ' && line[i] != '\t') ++i;
        if (i > start) out.push_back(line.substr(start, i - start));
    }
    return out;
}

bool parse_u64(std::string_view s, std::uint64_t& out) {
    if (s.empty() || s.size() > 20) return false;
    const auto r = std::from_chars(s.data(), s.data() + s.size(), out);
    return r.ec == std::errc() && r.ptr == s.data() + s.size();
}

class PlyChecker {
public:
    PlyChecker(std::string_view bytes, const std::string& source) : bytes_(bytes), source_(source) {}

    PlyFacts run() {
        header();
        if (encoding_ == Encoding::ascii) ascii_data();
        else binary_data();
        PlyFacts facts;
        for (const Element& e : elements_) {
            facts.materials = facts.materials || e.name == "material";
            if (e.name == "face")
                for (const Property& p : e.properties) facts.material_index = facts.material_index || p.name == "material_index";
        }
        return facts;
    }

private:
    [[noreturn]] void refuse(std::size_t line, const std::string& what) const {
        throw InputError(fmt::format("{}:{}: {}", source_, line, what));
    }
    [[noreturn]] void refuse(const std::string& what) const { throw InputError(fmt::format("{}: {}", source_, what)); }

    // The next line of the header ('\n'-terminated, a trailing '\r' dropped); false at the end
    // of the bytes (a last line without '\n' is not a header line: the header was cut short).
    bool next_line(std::string_view& line) {
        const std::size_t nl = bytes_.find('\n', at_);
        if (nl == std::string_view::npos) return false;
        line = bytes_.substr(at_, nl - at_);
        if (!line.empty() && line.back() == '\r') line.remove_suffix(1);
        at_ = nl + 1;
        ++line_;
        return true;
    }

    void header() {
        std::string_view line;
        if (!next_line(line) || line != "ply")
            refuse(1, "not a PLY file: the first line must be exactly 'ply'");
        bool have_format = false;
        for (;;) {
            if (at_ > kMaxHeaderBytes)
                refuse(line_, fmt::format("PLY header without 'end_header' in its first {} bytes", kMaxHeaderBytes));
            if (!next_line(line)) {
                // No newline left: a last line that begins with end_header is the data glued to it.
                const std::string_view rest = bytes_.substr(at_);
                if (rest.starts_with("end_header"))
                    refuse(line_ + 1, fmt::format("'{}' is not 'end_header' followed by a newline (the header's last line "
                                                  "must be 'end_header' alone, then a newline, then the data)",
                                                  shown(rest)));
                refuse(fmt::format("PLY header without 'end_header' (the file ends in header line {}; a file cut short, or not "
                                   "a PLY file){}",
                                   line_ + 1, hint()));
            }
            if (line == "end_header") break;
            if (line.starts_with("end_header"))
                refuse(line_, fmt::format("'{}' is not exactly 'end_header' (the header's last line must be 'end_header' "
                                          "alone, then a newline, then the data)",
                                          shown(line)));
            const std::vector<std::string_view> w = words(line);
            if (w.empty()) refuse(line_, "an empty line in the PLY header");
            if (w[0] == "comment" || w[0] == "obj_info") {
                if (line.find("end_header") != std::string_view::npos && comment_end_ == 0) comment_end_ = line_;
                continue;
            }
            if (w[0] == "format") {
                if (have_format) refuse(line_, "a second 'format' line");
                if (w.size() != 3 || w[2] != "1.0")
                    refuse(line_, fmt::format("'{}': the format line must be 'format ascii|binary_little_endian|"
                                              "binary_big_endian 1.0'",
                                              shown(line)));
                if (w[1] == "ascii") encoding_ = Encoding::ascii;
                else if (w[1] == "binary_little_endian") encoding_ = Encoding::little;
                else if (w[1] == "binary_big_endian") encoding_ = Encoding::big;
                else refuse(line_, fmt::format("unknown PLY format '{}' (ascii, binary_little_endian or binary_big_endian)", shown(w[1])));
                have_format = true;
                continue;
            }
            if (!have_format) refuse(line_, fmt::format("'{}' before the 'format' line", shown(line)));
            if (w[0] == "element") {
                Element e;
                if (w.size() != 3 || !parse_u64(w[2], e.count))
                    refuse(line_, fmt::format("'{}': an element line is 'element NAME COUNT' with a count >= 0", shown(line)));
                if (e.count > std::numeric_limits<std::uint32_t>::max())
                    refuse(line_, fmt::format("element '{}' declares {} records; at most 2^32 - 1 are read", shown(w[1]), e.count));
                e.name = std::string(w[1]);
                e.line = line_;
                elements_.push_back(std::move(e));
                continue;
            }
            if (w[0] == "property") {
                if (elements_.empty()) refuse(line_, "a 'property' line before any 'element' line");
                Property p;
                if (w.size() == 5 && w[1] == "list") {
                    p.list = true;
                    p.count = type_of(w[2]);
                    p.value = type_of(w[3]);
                    p.name = std::string(w[4]);
                    if (p.count.size == 0 || !p.count.integer)
                        refuse(line_, fmt::format("'{}': a list's count type must be an integer type", shown(line)));
                } else if (w.size() == 3) {
                    p.value = type_of(w[1]);
                    p.name = std::string(w[2]);
                } else {
                    refuse(line_, fmt::format("'{}': a property line is 'property TYPE NAME' or 'property list COUNTTYPE "
                                              "TYPE NAME'",
                                              shown(line)));
                }
                if (p.value.size == 0) refuse(line_, fmt::format("'{}': unknown property type", shown(line)));
                elements_.back().properties.push_back(std::move(p));
                continue;
            }
            refuse(line_, fmt::format("'{}' is not a PLY header line (format, element, property, comment, obj_info or "
                                      "end_header){}",
                                      shown(line), hint()));
        }
        if (!have_format) refuse(line_, "PLY header without a 'format' line");
        if (elements_.empty()) refuse(line_, "PLY header without elements");
        for (const Element& e : elements_)
            if (e.properties.empty()) refuse(e.line, fmt::format("element '{}' has no properties", e.name));
    }

    std::string hint() const {
        return comment_end_ == 0 ? std::string()
                                 : fmt::format("; the 'end_header' on line {} is inside a comment", comment_end_);
    }

    // --- ascii: one record per line, exactly the values its properties take ---

    void ascii_data() {
        for (const Element& e : elements_) {
            for (std::uint64_t r = 0; r < e.count; ++r) {
                std::string_view line;
                if (!data_line(line))
                    refuse(e.line, fmt::format("element '{}' declares {} records, the file ends after {} (ascii: one record "
                                               "per line)",
                                               e.name, e.count, r));
                const std::vector<std::string_view> w = words(line);
                std::size_t k = 0;
                for (const Property& p : e.properties) {
                    std::uint64_t n = 1;
                    if (p.list) {
                        if (k >= w.size() || !integer_token(w[k], false, n))
                            refuse(line_, fmt::format("element '{}' record {}: list '{}' needs a count >= 0, found '{}'", e.name,
                                                      r + 1, p.name, k < w.size() ? shown(w[k]) : std::string("end of line")));
                        ++k;
                        // assimp stores the count in its declared type: 300 as a uchar is 44.
                        const std::uint64_t type_max = (std::uint64_t(1) << (8 * p.count.size - (p.count.is_signed ? 1 : 0))) - 1;
                        if (n > type_max)
                            refuse(line_, fmt::format("element '{}' record {}: list '{}' count {} does not fit its count type "
                                                      "(at most {})",
                                                      e.name, r + 1, p.name, n, type_max));
                        if (n > w.size() - k)
                            refuse(line_, fmt::format("element '{}' record {}: list '{}' declares {} entries, the line holds {} "
                                                      "more values",
                                                      e.name, r + 1, p.name, n, w.size() - k));
                    }
                    for (std::uint64_t i = 0; i < n; ++i, ++k) {
                        if (k >= w.size())
                            refuse(line_, fmt::format("element '{}' record {} has {} values; its properties need more "
                                                      "(property '{}')",
                                                      e.name, r + 1, w.size(), p.name));
                        std::uint64_t ignored = 0;
                        const bool ok = p.value.integer ? integer_token(w[k], p.value.is_signed, ignored) : float_token(w[k]);
                        if (!ok)
                            refuse(line_, fmt::format("element '{}' record {}: '{}' is not {} (property '{}')", e.name, r + 1,
                                                      shown(w[k]), p.value.integer ? "an integer" : "a number", p.name));
                    }
                }
                if (k != w.size())
                    refuse(line_, fmt::format("element '{}' record {} has {} values; its properties take {} (do the header's "
                                              "counts match the data?)",
                                              e.name, r + 1, w.size(), k));
            }
        }
        std::string_view line;
        while (next_line_or_last(line))
            if (!words(line).empty())
                refuse(line_, "data after the last declared record (the header's counts do not match the data)");
    }

    // The next line of data, blank lines refused (assimp would read one as a record).
    bool data_line(std::string_view& line) {
        if (!next_line_or_last(line)) return false;
        if (words(line).empty()) refuse(line_, "an empty line inside the data (ascii PLY: one record per line)");
        return true;
    }

    // Like next_line, but a last line without '\n' counts.
    bool next_line_or_last(std::string_view& line) {
        if (at_ >= bytes_.size()) return false;
        if (next_line(line)) return true;
        line = bytes_.substr(at_);
        at_ = bytes_.size();
        ++line_;
        return true;
    }

    static bool integer_token(std::string_view s, bool is_signed, std::uint64_t& out) {
        if (is_signed && !s.empty() && s[0] == '-') {
            std::int64_t v = 0;
            const auto r = std::from_chars(s.data(), s.data() + s.size(), v);
            return r.ec == std::errc() && r.ptr == s.data() + s.size();
        }
        if (!s.empty() && s[0] == '+') s.remove_prefix(1);
        return parse_u64(s, out);
    }

    static bool float_token(std::string_view s) {
        double v = 0.0;
        if (!s.empty() && s[0] == '+') s.remove_prefix(1);
        const auto r = std::from_chars(s.data(), s.data() + s.size(), v);
        // Out of range (1e400) parses as an error: the coordinate check names it later, so a
        // number it is.
        return (r.ec == std::errc() || r.ec == std::errc::result_out_of_range) && r.ptr == s.data() + s.size();
    }

    // --- binary: records walked byte by byte ---

    std::uint64_t read_count(const Type& t, std::size_t at) const {
        std::uint8_t b[4] = {};
        std::memcpy(b, bytes_.data() + at, t.size);
        std::uint32_t v = 0;
        for (std::size_t i = 0; i < t.size; ++i) {
            const std::size_t k = encoding_ == Encoding::little ? t.size - 1 - i : i;
            v = (v << 8) | b[k];
        }
        if (t.is_signed) {
            const int shift = 32 - 8 * t.size;
            const auto s = static_cast<std::int32_t>(v << shift) >> shift;
            return s < 0 ? std::numeric_limits<std::uint64_t>::max() : std::uint64_t(s);
        }
        return v;
    }

    void binary_data() {
        const std::size_t header_end = at_;
        std::size_t at = at_;
        for (const Element& e : elements_) {
            std::uint64_t min_size = 0;  // fixed properties, and the counts of lists (empty lists)
            for (const Property& p : e.properties) min_size += p.list ? p.count.size : p.value.size;
            const std::size_t left = bytes_.size() - at;
            if (e.count > left / min_size)
                refuse(e.line, fmt::format("element '{}' declares {} records of at least {} bytes, only {} bytes of data are "
                                           "left (the file is cut short, or the count is wrong)",
                                           e.name, e.count, min_size, left));
            for (std::uint64_t r = 0; r < e.count; ++r) {
                for (const Property& p : e.properties) {
                    const std::size_t size = p.list ? p.count.size : p.value.size;
                    if (bytes_.size() - at < size) cut_short(e, r, at - header_end);
                    if (!p.list) {
                        at += size;
                        continue;
                    }
                    const std::uint64_t n = read_count(p.count, at);
                    at += size;
                    if (n == std::numeric_limits<std::uint64_t>::max())
                        refuse(e.line, fmt::format("element '{}' record {}: list '{}' has a negative count", e.name, r + 1, p.name));
                    if (n > (bytes_.size() - at) / p.value.size)
                        refuse(e.line, fmt::format("element '{}' record {}: list '{}' declares {} entries of {} bytes, only {} "
                                                   "bytes are left in the file",
                                                   e.name, r + 1, p.name, n, p.value.size, bytes_.size() - at));
                    at += static_cast<std::size_t>(n) * p.value.size;
                }
            }
        }
        for (std::size_t i = at; i < bytes_.size(); ++i)
            if (std::strchr(" \t\r\n", bytes_[i]) == nullptr || bytes_[i] == '\0')
                refuse(fmt::format("{} bytes after the last declared record (the header's counts do not match the data)",
                                   bytes_.size() - at));
    }

    [[noreturn]] void cut_short(const Element& e, std::uint64_t r, std::size_t offset) const {
        refuse(e.line, fmt::format("element '{}' declares {} records, the data ends inside record {} ({} bytes after the "
                                   "header)",
                                   e.name, e.count, r + 1, offset));
    }

    std::string_view bytes_;
    const std::string& source_;
    std::size_t at_ = 0;    // next byte of the header walk
    std::size_t line_ = 0;  // lines read
    std::size_t comment_end_ = 0;  // the first comment line that holds 'end_header' (for the message)
    Encoding encoding_ = Encoding::ascii;
    std::vector<Element> elements_;
};

}  // namespace

PlyFacts check_ply(std::string_view bytes, const std::string& source) { return PlyChecker(bytes, source).run(); }

}  // namespace ffcube
