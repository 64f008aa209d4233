// JSON run reports (--report R.json) without putting a JSON library in public headers.
//
// Keys are dotted paths: set("time.drawing", 1.5) makes {"time": {"drawing": 1.5}}. Objects keep
// the order in which their keys were first set, so reports read in the order they were filled.
// Setting a key again replaces its value in place. Doubles are written in the shortest form that
// reads back exactly; NaN and ±Inf, which JSON cannot represent, are written as null.
#pragma once

#include <concepts>
#include <cstdint>
#include <filesystem>
#include <memory>
#include <span>
#include <string>
#include <string_view>
#include <type_traits>
#include <vector>

namespace ffcube {

class Report {
public:
    Report();
    ~Report();
    Report(Report&&) noexcept;
    Report& operator=(Report&&) noexcept;
    Report(const Report&) = delete;
    Report& operator=(const Report&) = delete;

    // Every segment of a key must be non-empty, and a prefix of a key must not already hold a
    // value that is not an object (FFCUBE_CHECK: a programming error, not bad input).
    void set(std::string_view key, double value);
    void set(std::string_view key, bool value);
    void set(std::string_view key, std::string_view value);
    void set(std::string_view key, const char* value) { set(key, std::string_view(value)); }
    // Any integer type (int, size_t, uint32_t, ...) without ambiguity between the overloads above.
    template <std::integral T>
    requires(!std::same_as<T, bool>) void set(std::string_view key, T value) {
        if constexpr (std::is_signed_v<T>)
            set_int(key, static_cast<std::int64_t>(value));
        else
            set_uint(key, static_cast<std::uint64_t>(value));
    }

    void set_array(std::string_view key, std::span<const double> values);
    void set_array(std::string_view key, std::span<const std::int64_t> values);
    void set_array(std::string_view key, std::span<const std::uint64_t> values);
    void set_array(std::string_view key, const std::vector<std::string>& values);

    // Whether a value (of any type) is set at key.
    bool contains(std::string_view key) const;

    // The report as JSON text, indented by 2, with a final newline.
    std::string dump() const;
    // dump() to path, atomically (see atomic_file.hpp). IoError when it cannot be written.
    void write(const std::filesystem::path& path) const;

private:
    void set_int(std::string_view key, std::int64_t value);
    void set_uint(std::string_view key, std::uint64_t value);

    struct Impl;
    std::unique_ptr<Impl> impl_;
};

}  // namespace ffcube
