#include "ffcube/io/mtx.hpp"

#include <fcntl.h>
#include <fmt/format.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <optional>
#include <vector>

#include "ffcube/core/error.hpp"
#include "ffcube/io/atomic_file.hpp"

namespace ffcube {
namespace {

constexpr std::size_t kFlushBytes = 1 << 20;

[[noreturn]] void fail(const std::filesystem::path& path, const char* what, int err) {
    throw IoError(fmt::format("{}: {}: {}", path.string(), what, std::strerror(err)));
}

// A temporary file with no name (removed by the system when closed, even after a crash): in the
// output's directory (O_TMPFILE, or a named file unlinked at once), else in the system's temporary
// directory (an output that is a pipe or a terminal).
int unnamed_temporary(const std::filesystem::path& next_to) {
    std::filesystem::path dir = next_to.parent_path();
    if (dir.empty()) dir = ".";
    std::error_code ec;
    const auto st = std::filesystem::status(next_to, ec);
    if (!ec && std::filesystem::exists(st) && !std::filesystem::is_regular_file(st))
        dir = std::filesystem::temp_directory_path();  // /dev/stdout: not beside it in /dev
    for (const std::filesystem::path& d : {dir, std::filesystem::temp_directory_path()}) {
#ifdef O_TMPFILE
        const int fd = ::open(d.c_str(), O_TMPFILE | O_RDWR | O_CLOEXEC, 0600);
        if (fd >= 0) return fd;
#endif
        std::string name = (d / ".ffcube-mtx-spool.XXXXXX").string();
        const int named = ::mkstemp(name.data());
        if (named >= 0) {
            ::unlink(name.c_str());
            return named;
        }
    }
    fail(next_to, "cannot create a temporary file for the Matrix Market entries", errno);
}

void write_all(int fd, const char* data, std::size_t size, const std::filesystem::path& path) {
    while (size > 0) {
        const ssize_t w = ::write(fd, data, size);
        if (w < 0) {
            if (errno == EINTR) continue;
            fail(path, "write failed (temporary entries file)", errno);
        }
        data += w;
        size -= static_cast<std::size_t>(w);
    }
}

}  // namespace

struct MtxWriter::Impl {
    std::filesystem::path path;
    std::uint32_t n = 0, rows = 0;
    std::uint64_t nnz = 0;
    int spool = -1;
    fmt::memory_buffer buf;
    bool finished = false, progress = false;
    std::uint64_t spooled = 0;  // bytes
    std::optional<AtomicFile> file;  // created first, so a bad path fails before any row

    ~Impl() {
        if (spool >= 0) ::close(spool);
    }
    void flush() {
        write_all(spool, buf.data(), buf.size(), path);
        spooled += buf.size();
        buf.clear();
    }
};

MtxWriter::MtxWriter(const std::filesystem::path& path, std::uint32_t n, bool progress)
    : impl_(std::make_unique<Impl>()) {
    impl_->path = path;
    impl_->progress = progress;
    impl_->n = n;
    impl_->file.emplace(path);
    impl_->spool = unnamed_temporary(path);
}

MtxWriter::~MtxWriter() = default;

std::uint64_t MtxWriter::nnz() const { return impl_->nnz; }

void MtxWriter::append_row(RowView r) {
    Impl& m = *impl_;
    FFCUBE_CHECK_MSG(!m.finished && m.rows < m.n, fmt::format("MtxWriter: row {} of {}", m.rows, m.n));
    const std::uint32_t i = m.rows++;
    for (std::size_t k = 0; k < r.col.size(); ++k)
        fmt::format_to(std::back_inserter(m.buf), "{} {} {:.9g}\n", i + 1, r.col[k] + 1, static_cast<double>(r.val[k]));
    m.nnz += r.col.size();
    if (m.buf.size() >= kFlushBytes) m.flush();
}

void MtxWriter::finish() {
    Impl& m = *impl_;
    FFCUBE_CHECK_MSG(!m.finished && m.rows == m.n, fmt::format("MtxWriter::finish after {} of {} rows", m.rows, m.n));
    m.finished = true;
    m.flush();
    std::ostream& out = m.file->stream();
    const std::string header = fmt::format(
        "%%MatrixMarket matrix coordinate real general\n"
        "% ffcube form factors: entry (i, j) = fraction of the energy leaving patch i that arrives "
        "at patch j (patches numbered from 1)\n"
        "{} {} {}\n",
        m.n, m.n, m.nnz);
    out.write(header.data(), static_cast<std::streamsize>(header.size()));
    Progress bar(fmt::format("writing {} (MiB of entries after the header)", m.path.string()), m.spooled >> 20, m.progress);
    std::vector<char> chunk(kFlushBytes);
    for (off_t at = 0;;) {
        const ssize_t r = ::pread(m.spool, chunk.data(), chunk.size(), at);
        if (r < 0) {
            if (errno == EINTR) continue;
            fail(m.path, "read failed (temporary entries file)", errno);
        }
        if (r == 0) break;
        out.write(chunk.data(), r);
        at += r;
        bar.add(static_cast<std::uint64_t>(r) == kFlushBytes ? 1 : 0);
    }
    m.file->commit();
}

void write_mtx(const std::filesystem::path& path, const CsrMatrix& F, Progress* progress) {
    const std::uint32_t n = F.size();
    FFCUBE_CHECK_MSG(F.rows_filled() == n, "write_mtx needs every row of the matrix");
    MtxWriter writer(path, n);
    for (std::uint32_t i = 0; i < n; ++i) {
        writer.append_row(F.row(i));
        if (progress) progress->add();
    }
    writer.finish();
}

}  // namespace ffcube
