// The fields of one line of the small CSV inputs (solver/csv_fields.hpp).
#include "ffcube/solver/csv_fields.hpp"

#include <fmt/format.h>

#include <charconv>
#include <cmath>

#include "ffcube/core/error.hpp"

namespace ffcube {

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

std::optional<double> parse_number(const std::string& field, std::string_view column, const std::string& where) {
    if (field.empty()) return std::nullopt;
    double v = 0.0;
    const char* end = field.data() + field.size();
    const auto [ptr, ec] = std::from_chars(field.data(), end, v);
    if (ec != std::errc() || ptr != end || !std::isfinite(v))
        throw InputError(fmt::format("{}: {} '{}' is not a finite number", where, column, field));
    return v;
}

}  // namespace ffcube
