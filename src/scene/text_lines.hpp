// The line tokenizer of the line-oriented text formats other than OBJ (ASCII STL, View3D .vs3):
// lines split at '\n' (a trailing '\r' is a blank), a UTF-8 byte-order mark skipped, comments cut,
// control bytes refused (binary data), tokens separated by blanks and at most 4096 bytes long.
// Every refusal names the file, the line and the rule (text_number.hpp's fail_at).
#pragma once

#include <fmt/format.h>

#include <cstdint>
#include <string>
#include <string_view>

#include "text_number.hpp"

namespace ffcube::detail {

constexpr std::size_t kMaxToken = 4096;

inline bool is_blank(char c) { return c == ' ' || c == '\t' || c == '\r' || c == '\v' || c == '\f'; }

class LineReader {
public:
    // comment_chars: each starts a comment that runs to the end of the line (View3D: "!/"; STL: none).
    // not_text: the rule a control byte breaks, e.g. "not a View3D file (control bytes: binary data?)".
    LineReader(std::string_view text, const std::string& source, std::string_view comment_chars, std::string not_text)
        : rest_(text), source_(source), comments_(comment_chars), not_text_(std::move(not_text)) {
        if (rest_.substr(0, 3) == "\xEF\xBB\xBF") rest_.remove_prefix(3);
    }

    // The next line (comments cut), false at the end of the text. line_number() is then its number.
    bool next(std::string_view& line) {
        if (done_) return false;
        const std::size_t eol = rest_.find('\n');
        line = rest_.substr(0, eol);
        if (eol == std::string_view::npos)
            done_ = true;
        else
            rest_.remove_prefix(eol + 1);
        ++number_;
        if (!comments_.empty())
            if (const std::size_t c = line.find_first_of(comments_); c != std::string_view::npos) line = line.substr(0, c);
        for (const char c : line) {
            const auto u = static_cast<unsigned char>(c);
            if ((u < 0x20 && !is_blank(c)) || u == 0x7F) fail(not_text_);
        }
        return true;
    }

    // Takes the next blank-separated token off line; false when only blanks are left.
    bool token(std::string_view& line, std::string_view& out) const {
        while (!line.empty() && is_blank(line.front())) line.remove_prefix(1);
        if (line.empty()) return false;
        std::size_t n = 0;
        while (n < line.size() && !is_blank(line[n])) ++n;
        if (n > kMaxToken) fail(fmt::format("a token of {} bytes is longer than the limit of 4096 bytes", n));
        out = line.substr(0, n);
        line.remove_prefix(n);
        return true;
    }

    // The next token, or a refusal "missing WHAT".
    std::string_view required(std::string_view& line, std::string_view what) const {
        std::string_view t;
        if (!token(line, t)) fail(fmt::format("missing {}", what));
        return t;
    }

    // The next token as a number (text_number.hpp's rules); what names it in messages.
    double number(std::string_view& line, const char* what) const {
        std::string_view t;
        if (!token(line, t)) fail(fmt::format("missing a number ({})", what));
        return parse_number(t, source_, number_, what);
    }

    // Refuses anything left on the line: "RULE, found 'TOKEN'".
    void no_more(std::string_view& line, std::string_view rule) const {
        std::string_view t;
        if (token(line, t)) fail(fmt::format("{}, found {}", rule, shown(t)));
    }

    [[noreturn]] void fail(const std::string& rule) const { fail_at(source_, number_, rule); }

    std::uint32_t line_number() const { return number_; }
    const std::string& source() const { return source_; }

    static std::string_view trim(std::string_view s) {
        while (!s.empty() && is_blank(s.front())) s.remove_prefix(1);
        while (!s.empty() && is_blank(s.back())) s.remove_suffix(1);
        return s;
    }

private:
    std::string_view rest_;
    const std::string& source_;
    std::string_view comments_;
    std::string not_text_;
    std::uint32_t number_ = 0;
    bool done_ = false;
};

}  // namespace ffcube::detail
