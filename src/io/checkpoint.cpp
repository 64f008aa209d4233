#include "ffcube/io/checkpoint.hpp"

#include <fcntl.h>
#include <fmt/format.h>
#include <unistd.h>

#include <cerrno>
#include <chrono>
#include <cmath>
#include <cstring>
#include <fstream>
#include <map>
#include <sstream>

#include "ffcube/core/error.hpp"
#include "ffcube/core/le_bytes.hpp"
#include "ffcube/io/atomic_file.hpp"
#include "ffcube/io/checksum.hpp"

namespace ffcube {
namespace fs = std::filesystem;

namespace {

constexpr std::uint32_t kMagic = 0x52434646;  // "FFCR" little-endian
constexpr std::size_t kHeader = 16, kTrailer = 8;
constexpr float kMaxValue = 1.001f;  // as the .ffm reader: F entries are fractions, with rounding room
constexpr const char* kManifestName = "manifest.txt";
constexpr const char* kLogName = "rows.log";
constexpr const char* kFormatLine = "ffcube-checkpoint 3";  // written; formats 1 and 2 are still read
constexpr const char* kFormatLine2 = "ffcube-checkpoint 2";  // before the rows' figures (flag 2 never set)
constexpr const char* kFormatLine1 = "ffcube-checkpoint 1";  // before the obstructed shares (flags always 0)
constexpr std::uint32_t kFlagObstructed = 1;                 // an f64 obstructed share after the values
constexpr std::uint32_t kFlagFigures = 2;  // then f32 error, f32 tolerance_error, i32 measure, u32 0 (RowSide)
constexpr std::int32_t kMeasureMin = -1, kMeasureMax = 7;    // RowSide::measure's range (RowMeasure)

double now_seconds() {
    return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count();
}

std::uint64_t record_bytes(std::uint32_t nnz, std::uint32_t flags) {
    return kHeader + 8 * std::uint64_t(nnz) + ((flags & kFlagObstructed) ? 8 : 0) + ((flags & kFlagFigures) ? 16 : 0) +
           kTrailer;
}

// Where a record's figures start (after the values and the obstructed share).
std::size_t figures_at(std::uint32_t nnz, std::uint32_t flags) {
    return kHeader + 8 * std::size_t(nnz) + ((flags & kFlagObstructed) ? 8 : 0);
}

// The side figures of a checked record.
RowSide record_side(const unsigned char* buf, std::uint32_t nnz, std::uint32_t flags) {
    RowSide side;
    if (flags & kFlagObstructed) side.obstructed = load_le<double>(buf + kHeader + 8 * std::size_t(nnz));
    if (flags & kFlagFigures) {
        const unsigned char* f = buf + figures_at(nnz, flags);
        side.error = load_le<float>(f);
        side.tolerance_error = load_le<float>(f + 4);
        side.measure = static_cast<std::int8_t>(load_le<std::int32_t>(f + 8));
    }
    return side;
}

// The manifest as ordered key/value lines; a value never holds a newline.
std::vector<std::pair<std::string, std::string>> manifest_fields(const CheckpointManifest& m) {
    return {{"fingerprint", fmt::format("{:016x}", m.fingerprint)},
            {"patches", std::to_string(m.patches)},
            {"meshing", m.meshing},
            {"max_patch_edge", fmt::format("{:.17g}", m.max_patch_edge)},
            {"method", m.meta.method},
            {"resolution", std::to_string(m.meta.resolution)},
            {"settings", m.meta.settings},
            {"obstructions", m.obstructions ? "1" : "0"}};
}

void fsync_dir(const fs::path& dir) {
    const int fd = ::open(dir.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC);
    if (fd < 0) return;  // best effort: the files themselves are synced
    ::fsync(fd);
    ::close(fd);
}

int open_log(const fs::path& path, int flags) {
    const int fd = ::open(path.c_str(), flags | O_CLOEXEC, 0644);
    if (fd < 0) throw IoError(fmt::format("{}: cannot open the checkpoint log: {}", path.string(), std::strerror(errno)));
    return fd;
}

void pread_all(int fd, void* data, std::size_t size, std::uint64_t offset, const fs::path& path) {
    auto* p = static_cast<unsigned char*>(data);
    while (size > 0) {
        const ssize_t r = ::pread(fd, p, size, static_cast<off_t>(offset));
        if (r < 0 && errno == EINTR) continue;
        if (r <= 0)
            throw IoError(fmt::format("{}: cannot read the checkpoint log: {}", path.string(),
                                      r == 0 ? "unexpected end of file" : std::strerror(errno)));
        p += r;
        size -= static_cast<std::size_t>(r);
        offset += static_cast<std::uint64_t>(r);
    }
}

// Checks a whole record in buf (record_bytes(nnz, flags) bytes): checksum, then content. Returns
// what is wrong, or an empty string.
std::string check_record(const unsigned char* buf, std::uint32_t nnz, std::uint32_t n, std::uint32_t flags) {
    const std::size_t body = record_bytes(nnz, flags) - kTrailer;
    const auto stored = load_le<std::uint64_t>(buf + body);
    if (checksum64(buf, body) != stored) return "checksum mismatch";
    if (load_le<std::uint32_t>(buf + 12) != flags) return fmt::format("flags {} where the checkpoint's records have {}", load_le<std::uint32_t>(buf + 12), flags);
    if (flags & kFlagObstructed) {
        const auto o = load_le<double>(buf + kHeader + 8 * std::size_t(nnz));
        if (!std::isfinite(o) || o < 0.0 || o > kMaxValue) return fmt::format("obstructed share {} out of range", o);
    }
    if (flags & kFlagFigures) {
        const unsigned char* f = buf + figures_at(nnz, flags);
        for (int k = 0; k < 2; ++k)  // an estimate: NaN (none), or finite and not negative
            if (const auto e = load_le<float>(f + 4 * k); !std::isnan(e) && !(std::isfinite(e) && e >= 0.0f))
                return fmt::format("error estimate {} out of range", e);
        const auto m = load_le<std::int32_t>(f + 8);
        if (m < kMeasureMin || m > kMeasureMax || load_le<std::uint32_t>(f + 12) != 0)
            return fmt::format("measure {} out of range", m);
    }
    const unsigned char* cols = buf + kHeader;
    const unsigned char* vals = cols + 4 * std::size_t(nnz);
    for (std::uint32_t k = 0; k < nnz; ++k) {
        const std::uint32_t c = load_le<std::uint32_t>(cols + 4 * k);
        if (c >= n || (k > 0 && c <= load_le<std::uint32_t>(cols + 4 * (k - 1)))) return fmt::format("column {} out of order or range", c);
        const auto v = load_le<float>(vals + 4 * k);
        if (!std::isfinite(v) || v < 0.0f || v > kMaxValue) return fmt::format("value {} out of range", v);
    }
    return {};
}

}  // namespace

RowCheckpoint::RowCheckpoint(fs::path dir, std::uint32_t n, bool obstructions, bool figures)
    : dir_(std::move(dir)), offsets_(n, kMissing),
      flags_((obstructions ? kFlagObstructed : 0) | (figures ? kFlagFigures : 0)) {}

std::uint64_t RowCheckpoint::record_size(std::uint32_t nnz) const { return record_bytes(nnz, flags_); }

RowCheckpoint::RowCheckpoint(RowCheckpoint&& o) noexcept
    : dir_(std::move(o.dir_)), fd_(o.fd_), end_(o.end_), offsets_(std::move(o.offsets_)), stored_(o.stored_),
      warnings_(std::move(o.warnings_)), last_sync_(o.last_sync_), buffer_(std::move(o.buffer_)), flags_(o.flags_) {
    o.fd_ = -1;
}

RowCheckpoint& RowCheckpoint::operator=(RowCheckpoint&& o) noexcept {
    if (this != &o) {
        if (fd_ >= 0) ::close(fd_);
        dir_ = std::move(o.dir_);
        fd_ = o.fd_;
        o.fd_ = -1;
        end_ = o.end_;
        offsets_ = std::move(o.offsets_);
        stored_ = o.stored_;
        warnings_ = std::move(o.warnings_);
        last_sync_ = o.last_sync_;
        buffer_ = std::move(o.buffer_);
        flags_ = o.flags_;
    }
    return *this;
}

RowCheckpoint::~RowCheckpoint() {
    if (fd_ >= 0) {
        ::fsync(fd_);
        ::close(fd_);
    }
}

std::string RowCheckpoint::log_path() const { return (dir_ / kLogName).string(); }

RowCheckpoint RowCheckpoint::create(const fs::path& dir, const CheckpointManifest& manifest) {
    std::error_code ec;
    if (fs::exists(dir, ec) && !fs::is_directory(dir, ec))
        throw InputError(fmt::format("--checkpoint {}: exists and is not a directory", dir.string()));
    if (fs::exists(dir / kManifestName, ec))
        throw InputError(fmt::format("--checkpoint {}: already holds a checkpoint; add --resume to continue it, or "
                                     "remove it to start again",
                                     dir.string()));
    if (!fs::create_directory(dir, ec) && ec)
        throw InputError(fmt::format("--checkpoint {}: cannot create the directory: {}", dir.string(), ec.message()));

    RowCheckpoint c(dir, manifest.patches, manifest.obstructions, /*figures=*/true);
    // An empty log first, the manifest last: rows are appended only once the manifest exists, so
    // a log without a manifest (a kill between the two) holds no rows and is emptied here.
    c.fd_ = open_log(dir / kLogName, O_RDWR | O_CREAT | O_TRUNC);
    write_file_atomically(dir / kManifestName, [&](std::ostream& out) {
        out << kFormatLine << '\n';
        for (const auto& [key, value] : manifest_fields(manifest)) {
            FFCUBE_CHECK_MSG(value.find('\n') == std::string::npos, "manifest values are single lines");
            out << key << ' ' << value << '\n';
        }
    });
    ::fsync(c.fd_);
    fsync_dir(dir);
    c.last_sync_ = now_seconds();
    return c;
}

RowCheckpoint RowCheckpoint::resume(const fs::path& dir, const CheckpointManifest& manifest) {
    const fs::path mpath = dir / kManifestName;
    std::error_code ec;
    if (!fs::is_regular_file(mpath, ec))
        throw InputError(fmt::format("--resume: {} holds no checkpoint (no {}); run without --resume to start one",
                                     dir.string(), kManifestName));
    std::ifstream in(mpath, std::ios::binary);
    std::string line;
    if (!std::getline(in, line) || (line != kFormatLine && line != kFormatLine2 && line != kFormatLine1))
        throw InputError(fmt::format("{}: not an ffcube checkpoint manifest (expected '{}', '{}' or '{}' on line 1)",
                                     mpath.string(), kFormatLine, kFormatLine2, kFormatLine1));
    const bool format1 = line == kFormatLine1;
    // Formats 1 and 2 came before the rows' figures: their records (and the rows appended to
    // them) keep none, and their rows come back without estimates (RowSide's NaN).
    const bool figures = line == kFormatLine;
    std::map<std::string, std::string> found;
    while (std::getline(in, line)) {
        const auto space = line.find(' ');
        found[line.substr(0, space)] = space == std::string::npos ? "" : line.substr(space + 1);
    }
    // Format 1 came before obstruction-only surfaces could be checkpointed: it has none.
    if (format1) found.emplace("obstructions", "0");
    std::string differences;
    for (const auto& [key, value] : manifest_fields(manifest)) {
        const auto it = found.find(key);
        const std::string old = it == found.end() ? "(missing)" : it->second;
        if (old != value) differences += fmt::format("\n  {}: checkpoint '{}', this run '{}'", key, old, value);
    }
    if (!differences.empty())
        throw InputError(fmt::format("--resume: the checkpoint in {} was made for different rows; its rows cannot be "
                                     "reused (remove it, or run the command that made it):{}",
                                     dir.string(), differences));

    RowCheckpoint c(dir, manifest.patches, manifest.obstructions, figures);
    const fs::path lpath = dir / kLogName;
    c.fd_ = open_log(lpath, O_RDWR | O_CREAT);
    const off_t size = ::lseek(c.fd_, 0, SEEK_END);
    if (size < 0) throw IoError(fmt::format("{}: cannot seek: {}", lpath.string(), std::strerror(errno)));
    const auto file_size = static_cast<std::uint64_t>(size);
    const std::uint32_t n = manifest.patches;
    std::uint64_t pos = 0;
    unsigned char header[kHeader];
    while (pos < file_size) {
        if (file_size - pos < kHeader) {
            c.warnings_.push_back(fmt::format("{}: the last record is torn ({} bytes at offset {}); it is ignored",
                                              lpath.string(), file_size - pos, pos));
            break;
        }
        pread_all(c.fd_, header, kHeader, pos, lpath);
        const std::uint32_t magic = load_le<std::uint32_t>(header), row = load_le<std::uint32_t>(header + 4), nnz = load_le<std::uint32_t>(header + 8);
        if (magic != kMagic || row >= n || nnz > n || load_le<std::uint32_t>(header + 12) != c.flags_) {
            c.warnings_.push_back(fmt::format("{}: corrupted record at offset {} (bad header); it and the {} bytes after "
                                              "it are dropped and their rows computed again",
                                              lpath.string(), pos, file_size - pos));
            break;
        }
        const std::uint64_t rsize = c.record_size(nnz);
        if (file_size - pos < rsize) {
            c.warnings_.push_back(fmt::format("{}: the last record (row {}) is torn ({} of {} bytes); it is ignored",
                                              lpath.string(), row, file_size - pos, rsize));
            break;
        }
        c.buffer_.resize(rsize);
        pread_all(c.fd_, c.buffer_.data(), rsize, pos, lpath);
        const std::string wrong = check_record(c.buffer_.data(), nnz, n, c.flags_);
        if (!wrong.empty()) {
            c.warnings_.push_back(fmt::format("{}: corrupted record at offset {} (row {}: {}); it and the {} bytes after "
                                              "it are dropped and their rows computed again",
                                              lpath.string(), pos, row, wrong, file_size - pos));
            break;
        }
        if (c.offsets_[row] == kMissing) {
            c.offsets_[row] = pos;
            ++c.stored_;
        }
        pos += rsize;
    }
    if (pos < file_size) {
        if (::ftruncate(c.fd_, static_cast<off_t>(pos)) != 0 || ::fsync(c.fd_) != 0)
            throw IoError(fmt::format("{}: cannot cut off the damaged tail: {}", lpath.string(), std::strerror(errno)));
    }
    c.end_ = pos;
    // Appends go to the end; O_APPEND is not needed with one writer and an explicit seek.
    if (::lseek(c.fd_, static_cast<off_t>(pos), SEEK_SET) < 0)
        throw IoError(fmt::format("{}: cannot seek: {}", lpath.string(), std::strerror(errno)));
    c.last_sync_ = now_seconds();
    return c;
}

std::vector<std::uint32_t> RowCheckpoint::missing() const {
    std::vector<std::uint32_t> rows;
    for (std::uint32_t i = 0; i < size(); ++i)
        if (!has(i)) rows.push_back(i);
    return rows;
}

void RowCheckpoint::append(std::uint32_t i, const SparseRow& row) {
    FFCUBE_CHECK(i < size() && !has(i) && row.col.size() == row.val.size());
    FFCUBE_CHECK_MSG((flags_ & kFlagObstructed) || row.side.obstructed == 0.0,
                     "an obstructed share for a checkpoint made without obstructions");
    const auto nnz = static_cast<std::uint32_t>(row.col.size());
    const std::uint64_t rsize = record_size(nnz);
    buffer_.resize(rsize);
    unsigned char* p = buffer_.data();
    const std::uint32_t header[4] = {kMagic, i, nnz, flags_};
    std::memcpy(p, header, kHeader);
    std::memcpy(p + kHeader, row.col.data(), 4 * std::size_t(nnz));
    for (std::uint32_t k = 0; k < nnz; ++k) {
        const float v = static_cast<float>(row.val[k]);  // exactly what CsrMatrix::append_row stores
        store_le(p + kHeader + 4 * std::size_t(nnz) + 4 * k, v);
    }
    if (flags_ & kFlagObstructed) store_le(p + kHeader + 8 * std::size_t(nnz), row.side.obstructed);
    if (flags_ & kFlagFigures) {
        unsigned char* f = p + figures_at(nnz, flags_);
        store_le(f, row.side.error);
        store_le(f + 4, row.side.tolerance_error);
        store_le(f + 8, static_cast<std::int32_t>(row.side.measure));
        store_le(f + 12, std::uint32_t{0});
    }
    const std::uint64_t sum = checksum64(p, rsize - kTrailer);
    store_le(p + rsize - kTrailer, sum);
    std::size_t done = 0;
    while (done < rsize) {
        const ssize_t w = ::write(fd_, p + done, rsize - done);
        if (w < 0 && errno == EINTR) continue;
        if (w < 0) throw IoError(fmt::format("{}: cannot append row {}: {}", log_path(), i, std::strerror(errno)));
        done += static_cast<std::size_t>(w);
    }
    offsets_[i] = end_;
    end_ += rsize;
    ++stored_;
    maybe_sync();
}

void RowCheckpoint::maybe_sync() {
    const double t = now_seconds();
    if (t - last_sync_ >= 1.0) sync();
}

void RowCheckpoint::sync() {
    if (::fsync(fd_) != 0) throw IoError(fmt::format("{}: fsync failed: {}", log_path(), std::strerror(errno)));
    last_sync_ = now_seconds();
}

CsrMatrix RowCheckpoint::assemble() const {
    FFCUBE_CHECK_MSG(stored_ == size(), "assemble() needs every row");
    const fs::path lpath = log_path();
    const std::uint32_t n = size();
    // Two passes: the headers give every row's length, so the arrays are allocated once at their
    // exact size (a growing vector would need up to 1.5 times as much at its last reallocation).
    std::vector<std::uint64_t> row_ptr(std::size_t(n) + 1, 0);
    unsigned char header[kHeader];
    auto changed = [&](std::uint32_t i, const std::string& what) {
        return InputError(fmt::format("{}: the record of row {} at offset {} changed on disk while in use ({})",
                                      lpath.string(), i, offsets_[i], what));
    };
    for (std::uint32_t i = 0; i < n; ++i) {
        pread_all(fd_, header, kHeader, offsets_[i], lpath);
        const std::uint32_t nnz = load_le<std::uint32_t>(header + 8);
        if (load_le<std::uint32_t>(header) != kMagic || load_le<std::uint32_t>(header + 4) != i || nnz > n) throw changed(i, "bad header");
        row_ptr[i + 1] = row_ptr[i] + nnz;
    }
    std::vector<std::uint32_t> col(row_ptr[n]);
    std::vector<float> val(row_ptr[n]);
    for_each_row([&](std::uint32_t i, RowView r) {
        if (r.col.size() != row_ptr[i + 1] - row_ptr[i]) throw changed(i, "length");
        std::copy(r.col.begin(), r.col.end(), col.begin() + static_cast<long>(row_ptr[i]));
        std::copy(r.val.begin(), r.val.end(), val.begin() + static_cast<long>(row_ptr[i]));
    });
    return CsrMatrix::from_arrays(n, std::move(row_ptr), std::move(col), std::move(val));
}

void RowCheckpoint::for_each_row(const std::function<void(std::uint32_t, RowView)>& f) const {
    FFCUBE_CHECK_MSG(stored_ == size(), "for_each_row() needs every row");
    const fs::path lpath = log_path();
    const std::uint32_t n = size();
    auto changed = [&](std::uint32_t i, const std::string& what) {
        return InputError(fmt::format("{}: the record of row {} at offset {} changed on disk while in use ({})",
                                      lpath.string(), i, offsets_[i], what));
    };
    unsigned char header[kHeader];
    std::vector<unsigned char> buf;
    std::vector<std::uint32_t> col;
    std::vector<float> val;
    for (std::uint32_t i = 0; i < n; ++i) {
        pread_all(fd_, header, kHeader, offsets_[i], lpath);
        const std::uint32_t nnz = load_le<std::uint32_t>(header + 8);
        if (load_le<std::uint32_t>(header) != kMagic || load_le<std::uint32_t>(header + 4) != i || nnz > n) throw changed(i, "bad header");
        buf.resize(record_size(nnz));
        pread_all(fd_, buf.data(), buf.size(), offsets_[i], lpath);
        if (load_le<std::uint32_t>(buf.data() + 8) != nnz) throw changed(i, "length");
        const std::string wrong = check_record(buf.data(), nnz, n, flags_);
        if (!wrong.empty()) throw changed(i, wrong);
        col.resize(nnz);
        val.resize(nnz);
        std::memcpy(col.data(), buf.data() + kHeader, 4 * std::size_t(nnz));
        std::memcpy(val.data(), buf.data() + kHeader + 4 * std::size_t(nnz), 4 * std::size_t(nnz));
        f(i, RowView{col, val, record_side(buf.data(), nnz, flags_)});
    }
}

void RowCheckpoint::read_rows(std::uint32_t first, std::uint32_t last, std::vector<std::uint32_t>& nnz,
                              std::vector<std::uint32_t>& col, std::vector<float>& val,
                              std::vector<RowSide>& side) const {
    FFCUBE_CHECK(first <= last && last <= size());
    const fs::path lpath = log_path();
    const std::uint32_t n = size();
    std::vector<unsigned char> buf(kHeader);
    for (std::uint32_t i = first; i < last; ++i) {
        FFCUBE_CHECK_MSG(has(i), "read_rows() needs every row of its range");
        auto changed = [&](const std::string& what) {
            return InputError(fmt::format("{}: the record of row {} at offset {} changed on disk while in use ({})",
                                          lpath.string(), i, offsets_[i], what));
        };
        pread_all(fd_, buf.data(), kHeader, offsets_[i], lpath);
        const std::uint32_t count = load_le<std::uint32_t>(buf.data() + 8);
        if (load_le<std::uint32_t>(buf.data()) != kMagic || load_le<std::uint32_t>(buf.data() + 4) != i || count > n) throw changed("bad header");
        buf.resize(record_size(count));
        pread_all(fd_, buf.data(), buf.size(), offsets_[i], lpath);
        const std::string wrong = check_record(buf.data(), count, n, flags_);
        if (!wrong.empty()) throw changed(wrong);
        const std::size_t at = col.size();
        col.resize(at + count);
        val.resize(at + count);
        std::memcpy(col.data() + at, buf.data() + kHeader, 4 * std::size_t(count));
        std::memcpy(val.data() + at, buf.data() + kHeader + 4 * std::size_t(count), 4 * std::size_t(count));
        nnz.push_back(count);
        side.push_back(record_side(buf.data(), count, flags_));
    }
}

}  // namespace ffcube
