#include "ffcube/io/csv.hpp"

#include <fmt/format.h>

#include "ffcube/core/error.hpp"
#include "ffcube/io/atomic_file.hpp"

namespace ffcube {
namespace {

// Writes lines through a memory buffer, flushed in blocks (patch tables can be millions of lines).
class CsvWriter {
public:
    explicit CsvWriter(std::ostream& out) : out_(out) {}
    CsvWriter(const CsvWriter&) = delete;
    CsvWriter& operator=(const CsvWriter&) = delete;

    template <typename... Args>
    void line(fmt::format_string<Args...> f, Args&&... args) {
        fmt::format_to(std::back_inserter(buf_), f, std::forward<Args>(args)...);
        buf_.push_back('\n');
        if (buf_.size() >= (1u << 20)) flush();
    }
    void flush() {
        out_.write(buf_.data(), static_cast<std::streamsize>(buf_.size()));
        buf_.clear();
    }

private:
    std::ostream& out_;
    fmt::memory_buffer buf_;
};

}  // namespace

std::string csv_field(std::string_view s) {
    if (s.find_first_of(",\"\r\n") == std::string_view::npos) return std::string(s);
    std::string q = "\"";
    for (char c : s) {
        if (c == '"') q += '"';
        q += c;
    }
    q += '"';
    return q;
}

void write_groups_csv(const std::filesystem::path& path, const std::vector<std::vector<double>>& G,
                      const std::vector<std::string>& names) {
    FFCUBE_CHECK(G.size() == names.size());
    write_file_atomically(path, [&](std::ostream& out) {
        CsvWriter w(out);
        w.line("from,to,F");
        for (std::size_t a = 0; a < G.size(); ++a) {
            FFCUBE_CHECK(G[a].size() == names.size());
            for (std::size_t b = 0; b < G[a].size(); ++b)
                if (G[a][b] > 0) w.line("{},{},{:.9g}", csv_field(names[a]), csv_field(names[b]), G[a][b]);
        }
        w.flush();
    });
}

void write_object_radiosity_csv(const std::filesystem::path& path, const std::vector<std::string>& names,
                                std::span<const double> area, std::span<const Vec3> B) {
    FFCUBE_CHECK(area.size() == names.size() && B.size() == names.size());
    write_file_atomically(path, [&](std::ostream& out) {
        CsvWriter w(out);
        w.line("object,area,B_r,B_g,B_b");
        for (std::size_t a = 0; a < names.size(); ++a)
            w.line("{},{:.9g},{:.9g},{:.9g},{:.9g}", csv_field(names[a]), area[a], B[a].x, B[a].y, B[a].z);
        w.flush();
    });
}

void write_patch_radiosity_csv(const std::filesystem::path& path, std::span<const std::uint32_t> object,
                               std::span<const double> area, std::span<const Vec3> B,
                               const std::vector<std::string>& object_names) {
    FFCUBE_CHECK(area.size() == object.size() && B.size() == object.size());
    // Quote each name once, not once per patch.
    std::vector<std::string> fields;
    fields.reserve(object_names.size());
    for (const std::string& s : object_names) fields.push_back(csv_field(s));
    write_file_atomically(path, [&](std::ostream& out) {
        CsvWriter w(out);
        w.line("patch,object,area,B_r,B_g,B_b");
        for (std::size_t i = 0; i < object.size(); ++i) {
            FFCUBE_CHECK(object[i] < fields.size());
            w.line("{},{},{:.9g},{:.9g},{:.9g},{:.9g}", i, fields[object[i]], area[i], B[i].x, B[i].y, B[i].z);
        }
        w.flush();
    });
}

}  // namespace ffcube
