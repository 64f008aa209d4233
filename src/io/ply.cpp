#include "ffcube/io/ply.hpp"

#include <ostream>
#include <string>

#include "ffcube/core/error.hpp"
#include "ffcube/core/le_bytes.hpp"
#include "ffcube/io/atomic_file.hpp"

namespace ffcube {

void write_ply(const std::filesystem::path& path, const PlyMesh& mesh, const std::string& comment) {
    const std::size_t n = mesh.positions.size();
    FFCUBE_CHECK(mesh.colors.size() == n);
    FFCUBE_CHECK(mesh.values.empty() || mesh.values.size() == n);
    std::size_t listed = 0;
    for (std::uint8_t s : mesh.face_sizes) {
        FFCUBE_CHECK(s == 3 || s == 4);
        listed += s;
    }
    FFCUBE_CHECK(listed == mesh.face_indices.size());
    for (std::uint32_t i : mesh.face_indices) FFCUBE_CHECK(i < n);

    std::string header = "ply\nformat binary_little_endian 1.0\n";
    // A comment line ends at the first newline: keep it one line.
    std::string c = comment;
    for (char& ch : c)
        if (ch == '\n' || ch == '\r') ch = ' ';
    if (!c.empty()) header += "comment " + c + "\n";
    header += "element vertex " + std::to_string(n) + "\n";
    header += "property float x\nproperty float y\nproperty float z\n";
    header += "property uchar red\nproperty uchar green\nproperty uchar blue\n";
    if (!mesh.values.empty())
        header += "property float radiosity_r\nproperty float radiosity_g\nproperty float radiosity_b\n";
    header += "element face " + std::to_string(mesh.face_sizes.size()) + "\n";
    header += "property list uchar uint vertex_indices\nend_header\n";

    write_file_atomically(path, [&](std::ostream& os) {
        os << header;
        std::string buf;
        buf.reserve(1 << 16);
        const auto flush = [&] {
            os.write(buf.data(), static_cast<std::streamsize>(buf.size()));
            buf.clear();
        };
        for (std::size_t i = 0; i < n; ++i) {
            for (int k = 0; k < 3; ++k) append_le(buf, static_cast<float>(mesh.positions[i][k]));
            for (int k = 0; k < 3; ++k) append_le(buf, mesh.colors[i][static_cast<std::size_t>(k)]);
            if (!mesh.values.empty())
                for (int k = 0; k < 3; ++k) append_le(buf, static_cast<float>(mesh.values[i][k]));
            if (buf.size() > (1 << 16) - 64) flush();
        }
        std::size_t at = 0;
        for (std::uint8_t s : mesh.face_sizes) {
            append_le(buf, s);
            for (std::uint8_t k = 0; k < s; ++k) append_le(buf, mesh.face_indices[at++]);
            if (buf.size() > (1 << 16) - 64) flush();
        }
        flush();
    });
}

}  // namespace ffcube
