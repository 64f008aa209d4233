#include "ffcube/io/vtu.hpp"

#include <fmt/format.h>

#include "ffcube/core/error.hpp"
#include "ffcube/io/atomic_file.hpp"

namespace ffcube {
namespace {

// XML text: the five characters XML reserves, escaped (object names come from the user's file).
std::string xml_text(std::string_view s) {
    std::string out;
    for (const char c : s) {
        switch (c) {
        case '&': out += "&amp;"; break;
        case '<': out += "&lt;"; break;
        case '>': out += "&gt;"; break;
        case '"': out += "&quot;"; break;
        case '\'': out += "&apos;"; break;
        default: out += (static_cast<unsigned char>(c) < 32 && c != '\t') ? ' ' : c;
        }
    }
    return out;
}

template <typename F>
void data_array(std::ostream& out, const char* type, const std::string& name, std::size_t n, const F& value) {
    out << "        <DataArray type=\"" << type << "\" Name=\"" << xml_text(name) << "\" format=\"ascii\">\n";
    fmt::memory_buffer buf;
    for (std::size_t i = 0; i < n; ++i) {
        value(buf, i);
        buf.push_back(i % 8 == 7 || i + 1 == n ? '\n' : ' ');
        if (buf.size() > (1u << 16)) out.write(buf.data(), std::streamsize(buf.size())), buf.clear();
    }
    out.write(buf.data(), std::streamsize(buf.size()));
    out << "        </DataArray>\n";
}

}  // namespace

void write_fields_vtu(const std::filesystem::path& path, const Scene& scene, const std::vector<CellField>& fields) {
    const std::size_t n = scene.size();
    for (const CellField& f : fields) FFCUBE_CHECK(f.values.size() == n);
    const bool ids = scene.patch_elements.size() == n;
    write_file_atomically(path, [&](std::ostream& out) {
        out << "<?xml version=\"1.0\"?>\n"
               "<VTKFile type=\"UnstructuredGrid\" version=\"1.0\" byte_order=\"LittleEndian\" header_type=\"UInt64\">\n"
               "  <UnstructuredGrid>\n";
        out << "    <Piece NumberOfPoints=\"" << scene.positions.size() << "\" NumberOfCells=\"" << n << "\">\n";
        out << "      <Points>\n";
        {
            out << "        <DataArray type=\"Float64\" NumberOfComponents=\"3\" format=\"ascii\">\n";
            fmt::memory_buffer buf;
            for (const Vec3& p : scene.positions) {
                const Vec3 q = p + scene.origin;
                fmt::format_to(std::back_inserter(buf), "{:.17g} {:.17g} {:.17g}\n", q.x, q.y, q.z);
                if (buf.size() > (1u << 16)) out.write(buf.data(), std::streamsize(buf.size())), buf.clear();
            }
            out.write(buf.data(), std::streamsize(buf.size()));
            out << "        </DataArray>\n";
        }
        out << "      </Points>\n      <Cells>\n";
        out << "        <DataArray type=\"Int64\" Name=\"connectivity\" format=\"ascii\">\n";
        {
            fmt::memory_buffer buf;
            for (const Patch& p : scene.patches) {
                for (std::uint32_t k = 0; k < p.count; ++k) fmt::format_to(std::back_inserter(buf), "{}{}", k ? " " : "", p.v[k]);
                buf.push_back('\n');
                if (buf.size() > (1u << 16)) out.write(buf.data(), std::streamsize(buf.size())), buf.clear();
            }
            out.write(buf.data(), std::streamsize(buf.size()));
        }
        out << "        </DataArray>\n";
        std::uint64_t offset = 0;
        data_array(out, "Int64", "offsets", n, [&](fmt::memory_buffer& b, std::size_t i) {
            offset += scene.patches[i].count;
            fmt::format_to(std::back_inserter(b), "{}", offset);
        });
        data_array(out, "UInt8", "types", n,
                   [&](fmt::memory_buffer& b, std::size_t i) { fmt::format_to(std::back_inserter(b), "{}", scene.patches[i].count == 4 ? 9 : 5); });
        out << "      </Cells>\n      <CellData>\n";
        data_array(out, "Int64", "patch", n, [&](fmt::memory_buffer& b, std::size_t i) { fmt::format_to(std::back_inserter(b), "{}", i); });
        data_array(out, "Int32", "object", n,
                   [&](fmt::memory_buffer& b, std::size_t i) { fmt::format_to(std::back_inserter(b), "{}", scene.patches[i].object); });
        if (ids)
            data_array(out, "Int64", "element_id", n,
                       [&](fmt::memory_buffer& b, std::size_t i) { fmt::format_to(std::back_inserter(b), "{}", scene.patch_elements[i]); });
        data_array(out, "Float64", "area", n,
                   [&](fmt::memory_buffer& b, std::size_t i) { fmt::format_to(std::back_inserter(b), "{:.17g}", scene.patches[i].area); });
        for (const CellField& f : fields)
            data_array(out, "Float64", f.name, n,
                       [&](fmt::memory_buffer& b, std::size_t i) { fmt::format_to(std::back_inserter(b), "{:.17g}", f.values[i]); });
        out << "      </CellData>\n    </Piece>\n  </UnstructuredGrid>\n</VTKFile>\n";
    });
}

}  // namespace ffcube
