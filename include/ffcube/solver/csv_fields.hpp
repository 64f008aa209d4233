// The fields of one line of the small CSV inputs (radiate's surfaces, the sun series, albedos):
// commas outside double quotes, blanks trimmed, numbers checked. Every refusal names `where`
// (file:line).
#pragma once

#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace ffcube {

// Blanks, tabs and a trailing '\r' off both ends.
std::string_view trim(std::string_view s);
// Splits a CSV line at commas outside double quotes; a quoted field loses its quotes ("" → ").
// InputError (via `where`) for an unterminated quote.
std::vector<std::string> split_csv(std::string_view line, const std::string& where);
// The whole field as a finite number; nullopt when empty. InputError naming the column otherwise.
std::optional<double> parse_number(const std::string& field, std::string_view column, const std::string& where);

}  // namespace ffcube
