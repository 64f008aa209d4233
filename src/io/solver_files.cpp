#include "ffcube/io/solver_files.hpp"

#include <fmt/format.h>

#include <bit>
#include <cmath>
#include <cstdint>
#include <cstring>

#include "ffcube/core/error.hpp"
#include "ffcube/core/le_bytes.hpp"
#include "ffcube/io/atomic_file.hpp"
#include "ffcube/io/csv.hpp"

namespace ffcube {
namespace {

constexpr std::size_t kFlushBytes = 1 << 20;

void flush_if_full(std::ostream& out, fmt::memory_buffer& buf, bool force = false) {
    if (!force && buf.size() < kFlushBytes) return;
    out.write(buf.data(), static_cast<std::streamsize>(buf.size()));
    buf.clear();
}

}  // namespace

std::string view3d_header(int format, int encl, int emit, std::size_t n) {
    std::string h = fmt::format("View3D 3.5 {} {} {} {}", format, encl, emit, n);
    FFCUBE_CHECK_MSG(h.size() <= 30, "View3D header longer than 30 bytes");
    h.resize(30, ' ');
    h += format == 1 ? "\r\n" : "\n";
    return h;
}

void write_view3d(const std::filesystem::path& path, const View3dTable& t, bool binary) {
    const std::size_t n = t.area.size();
    FFCUBE_CHECK(t.F.size() == n && t.emissivity.size() == n);
    write_file_atomically(path, [&](std::ostream& out) {
        const std::string header = view3d_header(binary ? 1 : 0, t.encl, t.emit, n);
        if (binary) {
            out.write(header.data(), static_cast<std::streamsize>(header.size()));
            for (const double a : t.area) append_le(out, static_cast<float>(a));
            for (const auto& row : t.F)
                for (const double f : row) append_le(out, static_cast<float>(f));
            for (const double e : t.emissivity) append_le(out, static_cast<float>(e));
            return;
        }
        fmt::memory_buffer buf;
        const auto line = [&](const std::vector<double>& v, auto&& one) {
            for (std::size_t k = 0; k < v.size(); ++k) {
                if (k) buf.push_back(' ');
                one(v[k]);
            }
            buf.push_back('\n');
            flush_if_full(out, buf);
        };
        buf.append(header);
        // Values are rounded to float first, as View3D stores them (R4).
        line(t.area, [&](double a) { fmt::format_to(std::back_inserter(buf), "{:g}", static_cast<float>(a)); });
        for (const auto& row : t.F)
            line(row, [&](double f) { fmt::format_to(std::back_inserter(buf), "{:.6f}", static_cast<float>(f)); });
        line(t.emissivity, [&](double e) { fmt::format_to(std::back_inserter(buf), "{:.3f}", static_cast<float>(e)); });
        flush_if_full(out, buf, true);
    });
}

struct View3dSparseWriter::Impl {
    AtomicFile file;
    std::uint32_t rows = 0;
    std::uint64_t entries = 0;
    bool finished = false;
    fmt::memory_buffer buf;
    explicit Impl(const std::filesystem::path& path) : file(path) {}
};

View3dSparseWriter::View3dSparseWriter(const std::filesystem::path& path) : impl_(std::make_unique<Impl>(path)) {}

View3dSparseWriter::~View3dSparseWriter() = default;

void View3dSparseWriter::append_row(std::span<const std::uint32_t> col, std::span<const double> val) {
    Impl& m = *impl_;
    FFCUBE_CHECK(!m.finished && col.size() == val.size());
    const std::uint32_t n = ++m.rows;
    for (std::size_t k = 0; k < col.size(); ++k) {
        FFCUBE_CHECK_MSG(k == 0 || col[k] > col[k - 1], "View3dSparseWriter: columns must increase");
        if (!(val[k] >= kView3dSparseThreshold)) continue;
        fmt::format_to(std::back_inserter(m.buf), "{} {} {:.6f}\n", n, col[k] + 1, val[k]);
        ++m.entries;
    }
    flush_if_full(m.file.stream(), m.buf);
}

void View3dSparseWriter::finish() {
    Impl& m = *impl_;
    FFCUBE_CHECK(!m.finished);
    m.finished = true;
    flush_if_full(m.file.stream(), m.buf, true);
    m.file.commit();
}

std::uint64_t View3dSparseWriter::entries() const { return impl_->entries; }

void write_view3d(const std::filesystem::path& path, const View3dTable& t, int out) {
    FFCUBE_CHECK_MSG(out >= 0 && out <= 2, fmt::format("View3D output format {}", out));
    if (out != 2) return write_view3d(path, t, out == 1);
    const std::size_t n = t.area.size();
    FFCUBE_CHECK(t.F.size() == n);
    View3dSparseWriter writer(path);
    std::vector<std::uint32_t> col;
    std::vector<double> val;
    for (const auto& row : t.F) {
        FFCUBE_CHECK(row.size() == n);
        col.clear();
        val.clear();
        for (std::size_t m = 0; m < n; ++m)
            if (row[m] != 0.0) {
                col.push_back(static_cast<std::uint32_t>(m));
                val.push_back(row[m]);
            }
        writer.append_row(col, val);
    }
    writer.finish();
}

struct ElmerViewFactorsWriter::Impl {
    AtomicFile file;
    std::uint32_t n = 0, rows = 0;
    bool binary = false, finished = false;
    fmt::memory_buffer buf;
    Impl(const std::filesystem::path& path, std::uint32_t n_, bool binary_) : file(path), n(n_), binary(binary_) {}
};

ElmerViewFactorsWriter::ElmerViewFactorsWriter(const std::filesystem::path& path, std::uint32_t n, bool binary)
    : impl_(std::make_unique<Impl>(path, n, binary)) {
    if (binary) append_le(impl_->buf, static_cast<std::int32_t>(n));
}

ElmerViewFactorsWriter::~ElmerViewFactorsWriter() = default;

void ElmerViewFactorsWriter::append_row(RowView r) {
    Impl& m = *impl_;
    FFCUBE_CHECK_MSG(!m.finished && m.rows < m.n, fmt::format("ElmerViewFactorsWriter: row {} of {}", m.rows, m.n));
    const std::uint32_t i = m.rows++;
    std::int32_t k = 0;
    for (const float v : r.val) k += v > 0.0f ? 1 : 0;
    if (m.binary) {
        append_le(m.buf, k);
        for (std::size_t e = 0; e < r.col.size(); ++e)
            if (r.val[e] > 0.0f) {
                append_le(m.buf, static_cast<std::int32_t>(r.col[e] + 1));
                append_le(m.buf, static_cast<double>(r.val[e]));
            }
    } else {
        fmt::format_to(std::back_inserter(m.buf), "{}\n", k);
        // 9 significant digits: every float reads back exactly.
        for (std::size_t e = 0; e < r.col.size(); ++e)
            if (r.val[e] > 0.0f)
                fmt::format_to(std::back_inserter(m.buf), "{} {} {:.9g}\n", i + 1, r.col[e] + 1,
                               static_cast<double>(r.val[e]));
    }
    flush_if_full(m.file.stream(), m.buf);
}

void ElmerViewFactorsWriter::finish() {
    Impl& m = *impl_;
    FFCUBE_CHECK_MSG(!m.finished && m.rows == m.n,
                     fmt::format("ElmerViewFactorsWriter::finish after {} of {} rows", m.rows, m.n));
    m.finished = true;
    flush_if_full(m.file.stream(), m.buf, true);
    m.file.commit();
}

void write_elmer_view_factors(const std::filesystem::path& path, const CsrMatrix& F, bool binary, Progress* progress) {
    const std::uint32_t n = F.size();
    FFCUBE_CHECK_MSG(F.rows_filled() == n, "write_elmer_view_factors needs every row of the matrix");
    ElmerViewFactorsWriter writer(path, n, binary);
    for (std::uint32_t i = 0; i < n; ++i) {
        writer.append_row(F.row(i));
        if (progress) progress->add();
    }
    writer.finish();
}

void write_patch_table(const std::filesystem::path& path, const Scene& scene, std::span<const float> row_error) {
    const bool errors = row_error.size() >= scene.size();
    write_file_atomically(path, [&](std::ostream& out) {
        fmt::memory_buffer buf;
        // A mesh read through Gmsh adds the element each patch comes from (Scene::patch_elements);
        // a run with the near-field correction adds each row's estimated error.
        const bool ids = scene.patch_elements.size() == scene.size();
        buf.append(std::string_view("patch,object,area,cx,cy,cz,nx,ny,nz"));
        if (ids) buf.append(std::string_view(",element_id"));
        if (errors) buf.append(std::string_view(",error_estimate"));
        buf.push_back('\n');
        for (std::size_t i = 0; i < scene.size(); ++i) {
            const Patch& p = scene.patches[i];
            const Vec3 c = p.centroid + scene.origin;  // the user's coordinates (Scene::origin)
            fmt::format_to(std::back_inserter(buf), "{},{},{:.9g},{:.9g},{:.9g},{:.9g},{:.9g},{:.9g},{:.9g}", i,
                           csv_field(scene.objects[p.object]), p.area, c.x, c.y, c.z,
                           p.normal.x, p.normal.y, p.normal.z);
            if (ids) fmt::format_to(std::back_inserter(buf), ",{}", scene.patch_elements[i]);
            if (errors) {
                if (std::isnan(row_error[i])) buf.append(std::string_view(","));
                else fmt::format_to(std::back_inserter(buf), ",{:.3g}", row_error[i]);
            }
            buf.push_back('\n');
            flush_if_full(out, buf);
        }
        flush_if_full(out, buf, true);
    });
}

void write_patch_sky_csv(const std::filesystem::path& path, const Scene& scene, const std::vector<double>& svf) {
    FFCUBE_CHECK(svf.size() == scene.size());
    write_file_atomically(path, [&](std::ostream& out) {
        fmt::memory_buffer buf;
        const bool ids = scene.patch_elements.size() == scene.size();
        buf.append(std::string_view(ids ? "patch,object,area,sky_view_factor,element_id\n" : "patch,object,area,sky_view_factor\n"));
        for (std::size_t i = 0; i < scene.size(); ++i) {
            const Patch& p = scene.patches[i];
            fmt::format_to(std::back_inserter(buf), "{},{},{:.9g},{:.9g}", i, csv_field(scene.objects[p.object]), p.area, svf[i]);
            if (ids) fmt::format_to(std::back_inserter(buf), ",{}", scene.patch_elements[i]);
            buf.push_back('\n');
            flush_if_full(out, buf);
        }
        flush_if_full(out, buf, true);
    });
}

void write_object_sky_csv(const std::filesystem::path& path, const std::vector<std::string>& names,
                          const std::vector<double>& area, const std::vector<double>& svf) {
    FFCUBE_CHECK(names.size() == area.size() && names.size() == svf.size());
    write_file_atomically(path, [&](std::ostream& out) {
        fmt::memory_buffer buf;
        buf.append(std::string_view("object,area,sky_view_factor\n"));
        for (std::size_t a = 0; a < names.size(); ++a)
            fmt::format_to(std::back_inserter(buf), "{},{:.9g},{:.9g}\n", csv_field(names[a]), area[a], svf[a]);
        flush_if_full(out, buf, true);
    });
}

}  // namespace ffcube
