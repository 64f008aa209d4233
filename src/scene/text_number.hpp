// Numbers in the text formats other than OBJ (STL ASCII, View3D, --materials CSV), with the same
// rules as OBJ's (docs/scene-format.md, "Numbers"): decimal or scientific, finite, magnitude at
// most 1e15; a refusal names the file, the line and the rule.
#pragma once

#include <fmt/format.h>

#include <charconv>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <string>
#include <string_view>

#include "ffcube/core/csv_input.hpp"
#include "ffcube/core/error.hpp"

namespace ffcube::detail {

constexpr double kMaxCoordinate = 1e15;

[[noreturn]] inline void fail_at(const std::string& source, std::uint64_t line, const std::string& rule) {
    throw InputError(fmt::format("{}:{}: {}", source, line, rule));
}

inline std::string shown(std::string_view token) { return quoted_for_message(token); }

inline double parse_number(std::string_view token, const std::string& source, std::uint64_t line, const char* what) {
    std::string_view digits = token;
    if (digits.size() > 1 && digits.front() == '+') digits.remove_prefix(1);
    double value = 0.0;
    const auto [end, ec] = std::from_chars(digits.data(), digits.data() + digits.size(), value);
    if (digits.empty() || end != digits.data() + digits.size() ||
        (ec != std::errc() && ec != std::errc::result_out_of_range))
        fail_at(source, line, fmt::format("{} is not a number ({})", shown(token), what));
    if (ec == std::errc::result_out_of_range) {
        const std::string copy(digits);
        value = std::strtod(copy.c_str(), nullptr);
        if (std::abs(value) <= 1.0) return value;  // underflow to (almost) zero is harmless
        fail_at(source, line,
                fmt::format("{} overflows a double ({}; numbers must be finite with magnitude at most 1e15)", shown(token), what));
    }
    if (!std::isfinite(value))
        fail_at(source, line, fmt::format("{} is not a finite number ({}; NaN and infinity are refused)", shown(token), what));
    if (std::abs(value) > kMaxCoordinate)
        fail_at(source, line, fmt::format("{} is too large ({}; numbers must have magnitude at most 1e15)", shown(token), what));
    return value;
}

}  // namespace ffcube::detail
