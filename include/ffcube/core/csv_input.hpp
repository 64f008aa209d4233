// The small CSV inputs, read one way: radiate's surfaces (S.csv) and bands (B.csv), the sun
// series (SUN.csv) and albedos (A.csv) of `ffcube sun`, and --materials. docs/robustness.md, "CSV
// inputs".
//
// The rules, the same for every file:
//   - a UTF-8 byte-order mark before the first line is skipped; lines end in LF or CRLF;
//   - blank lines and lines whose first non-blank character is '#' are skipped;
//   - fields are split at commas outside double quotes ("" inside quotes is one "), and blanks and
//     tabs around a field are trimmed;
//   - the first other line is the header, which must be one of the accepted ones exactly (or, where
//     the header is optional, it is the header when its first field is the header's first name);
//   - every later line has as many fields as the header;
//   - a number is the whole field, decimal or scientific with an optional sign, and finite;
//   - a NUL byte anywhere refuses the file (a binary file given by mistake).
// Every refusal is an InputError that begins "SOURCE:LINE: " (or "SOURCE: " for the whole file)
// and says the rule broken.
#pragma once

#include <cstddef>
#include <functional>
#include <map>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <vector>

namespace ffcube {

// Blanks, tabs and a trailing '\r' off both ends.
std::string_view trim(std::string_view s);

// A field or token as a message quotes it: in single quotes, control and non-ASCII bytes as '?',
// cut at 40 characters ("'...'" then).
std::string quoted_for_message(std::string_view field);

// Splits a CSV line at commas outside double quotes; a quoted field loses its quotes ("" → ") and
// every field is trimmed. InputError "WHERE: a double quote is not closed" for an unterminated quote.
std::vector<std::string> split_csv(std::string_view line, const std::string& where);

// The whole field as a finite number, nullopt when it is empty. Otherwise InputError
// "WHERE: COLUMN 'FIELD' is not a finite number" (with " (HINT)" after it when a hint is given).
// A number too small for a double reads as its nearest double (0 or a subnormal).
std::optional<double> parse_csv_number(std::string_view field, std::string_view column, const std::string& where,
                                       std::string_view hint = {});

// One accepted header: its column names in order.
using CsvHeader = std::vector<std::string>;

// One line after the header.
struct CsvRow {
    std::size_t line = 0;             // 1-based, counted in the file (blank and comment lines too)
    std::string where;                // "SOURCE:LINE", the start of every message about this line
    std::vector<std::string> fields;  // as many as the header's names
    std::shared_ptr<const CsvHeader> header;

    // Field k as a number (parse_csv_number with the header's name k); nullopt when empty.
    std::optional<double> number(std::size_t k, std::string_view hint = {}) const;
    // Field k as a number that must be given: InputError "WHERE: COLUMN is missing" when empty.
    double required(std::size_t k) const;
    // InputError "WHERE: RULE".
    [[noreturn]] void fail(std::string_view rule) const;
};

// The scene's objects by name, for the rows that name one (S.csv, B.csv, A.csv).
class ObjectIndex {
public:
    explicit ObjectIndex(std::span<const std::string> objects);
    // The index of `name`. InputError "WHERE: the scene has no object 'NAME' (its objects: a, b,
    // ...)" (the first 12 listed) when the scene has none.
    std::size_t at(std::string_view name, std::string_view where) const;

private:
    std::span<const std::string> objects_;
    std::map<std::string, std::size_t, std::less<>> index_;
};

struct CsvTable {
    std::size_t header_index = 0;  // which of the accepted headers the file has
    std::vector<CsvRow> rows;      // may be empty (a file with its header alone)
};

// `headers`: the accepted headers (one, or alternatives). `header_optional`: the header line may
// be left out, with headers.size() == 1 (a first line whose first field is not the header's first
// name is then a row). `source` names the file in messages. The text is the file's whole content,
// as read_input_file (input_file.hpp) gives it: that is where regular files alone are accepted.
CsvTable parse_csv(std::string_view text, const std::string& source, std::span<const CsvHeader> headers,
                   bool header_optional = false);

}  // namespace ffcube
