// The small CSV inputs, read one way (core/csv_input.hpp).
#include "ffcube/core/csv_input.hpp"

#include <fmt/format.h>
#include <fmt/ranges.h>

#include <charconv>
#include <cmath>
#include <cstdlib>

#include "ffcube/core/error.hpp"

namespace ffcube {
namespace {

std::string quoted_headers(std::span<const CsvHeader> headers) {
    std::string out;
    for (std::size_t h = 0; h < headers.size(); ++h)
        out += fmt::format("{}'{}'", h ? " or " : "", fmt::join(headers[h], ","));
    return out;
}

}  // namespace

std::string quoted_for_message(std::string_view field) {
    constexpr std::size_t kShown = 40;
    std::string out;
    for (const char c : field.substr(0, kShown)) {
        const auto u = static_cast<unsigned char>(c);
        out += (u < 0x20 || u >= 0x7F) ? '?' : c;
    }
    return field.size() <= kShown ? fmt::format("'{}'", out) : fmt::format("'{}...'", out);
}

ObjectIndex::ObjectIndex(std::span<const std::string> objects) : objects_(objects) {
    for (std::size_t k = 0; k < objects.size(); ++k) index_.emplace(objects[k], k);
}

std::size_t ObjectIndex::at(std::string_view name, std::string_view where) const {
    if (const auto it = index_.find(name); it != index_.end()) return it->second;
    constexpr std::size_t kListed = 12;
    std::string names;
    for (std::size_t k = 0; k < objects_.size() && k < kListed; ++k) names += (k ? ", " : "") + objects_[k];
    if (objects_.size() > kListed) names += ", ...";
    throw InputError(fmt::format("{}: the scene has no object '{}' (its objects: {})", where, name, names));
}

std::string_view trim(std::string_view s) {
    while (!s.empty() && (s.front() == ' ' || s.front() == '\t')) s.remove_prefix(1);
    while (!s.empty() && (s.back() == ' ' || s.back() == '\t' || s.back() == '\r')) s.remove_suffix(1);
    return s;
}

std::vector<std::string> split_csv(std::string_view line, const std::string& where) {
    std::vector<std::string> fields(1);
    bool quoted = false;
    for (std::size_t k = 0; k < line.size(); ++k) {
        const char ch = line[k];
        if (quoted) {
            if (ch == '"' && k + 1 < line.size() && line[k + 1] == '"') {
                fields.back() += '"';
                ++k;
            } else if (ch == '"') {
                quoted = false;
            } else {
                fields.back() += ch;
            }
        } else if (ch == '"' && trim(fields.back()).empty()) {
            fields.back().clear();
            quoted = true;
        } else if (ch == ',') {
            fields.emplace_back();
        } else {
            fields.back() += ch;
        }
    }
    if (quoted) throw InputError(fmt::format("{}: a double quote is not closed", where));
    for (std::string& f : fields) f = std::string(trim(f));
    return fields;
}

std::optional<double> parse_csv_number(std::string_view field, std::string_view column, const std::string& where,
                                       std::string_view hint) {
    if (field.empty()) return std::nullopt;
    const auto refuse = [&] {
        throw InputError(fmt::format("{}: {} {} is not a finite number{}", where, column, quoted_for_message(field),
                                     hint.empty() ? std::string() : fmt::format(" ({})", hint)));
    };
    // from_chars takes no '+'; one before a digit or a point is the number's sign.
    std::string_view digits = field;
    if (digits.size() > 1 && digits.front() == '+' && digits[1] != '-' && digits[1] != '+') digits.remove_prefix(1);
    double v = 0.0;
    const char* end = digits.data() + digits.size();
    const auto [ptr, ec] = std::from_chars(digits.data(), end, v);
    if (ptr != end || (ec != std::errc() && ec != std::errc::result_out_of_range)) refuse();
    if (ec == std::errc::result_out_of_range) {
        // Overflow (refused below) or underflow: strtod gives the nearest double, ±HUGE_VAL or ~0.
        const std::string copy(digits);
        v = std::strtod(copy.c_str(), nullptr);
        if (std::abs(v) >= HUGE_VAL) refuse();
    }
    if (!std::isfinite(v)) refuse();
    return v;
}

std::optional<double> CsvRow::number(std::size_t k, std::string_view hint) const {
    return parse_csv_number(fields.at(k), header->at(k), where, hint);
}

double CsvRow::required(std::size_t k) const {
    const std::optional<double> v = number(k);
    if (!v) fail(fmt::format("{} is missing", header->at(k)));
    return *v;
}

void CsvRow::fail(std::string_view rule) const { throw InputError(fmt::format("{}: {}", where, rule)); }

CsvTable parse_csv(std::string_view text, const std::string& source, std::span<const CsvHeader> headers,
                   bool header_optional) {
    FFCUBE_CHECK(!headers.empty() && (!header_optional || headers.size() == 1));
    CsvTable table;
    std::shared_ptr<const CsvHeader> header;
    if (header_optional) header = std::make_shared<const CsvHeader>(headers[0]);
    bool seen_first = false;  // the first line that is neither blank nor a comment
    if (text.substr(0, 3) == "\xEF\xBB\xBF") text.remove_prefix(3);
    std::size_t line_no = 0;
    while (!text.empty()) {
        const std::size_t nl = text.find('\n');
        const std::string_view raw = text.substr(0, nl);
        text = nl == std::string_view::npos ? std::string_view{} : text.substr(nl + 1);
        ++line_no;
        if (raw.find('\0') != std::string_view::npos)
            throw InputError(fmt::format("{}:{}: not a CSV file (a NUL byte)", source, line_no));
        const std::string_view line = trim(raw);
        if (line.empty() || line.front() == '#') continue;
        const std::string where = fmt::format("{}:{}", source, line_no);
        std::vector<std::string> f = split_csv(line, where);
        if (!seen_first) {
            seen_first = true;
            if (header_optional) {
                if (f.front() == headers[0].front()) continue;
            } else {
                for (std::size_t h = 0; h < headers.size() && !header; ++h)
                    if (f == headers[h]) {
                        table.header_index = h;
                        header = std::make_shared<const CsvHeader>(headers[h]);
                    }
                if (!header)
                    throw InputError(fmt::format("{}: the first line must be the header {}", where, quoted_headers(headers)));
                continue;
            }
        }
        if (f.size() != header->size())
            throw InputError(fmt::format("{}: {} fields; each line is {} ({} fields)", where, f.size(),
                                         fmt::join(*header, ","), header->size()));
        table.rows.push_back(CsvRow{line_no, where, std::move(f), header});
    }
    if (!header) throw InputError(fmt::format("{}: empty; expected the header {}", source, quoted_headers(headers)));
    return table;
}

}  // namespace ffcube
