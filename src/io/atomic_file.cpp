#include "ffcube/io/atomic_file.hpp"

#include <fcntl.h>
#include <fmt/format.h>
#include <unistd.h>

#include <array>
#include <atomic>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <streambuf>
#include <string>

#include "ffcube/core/error.hpp"

namespace ffcube {
namespace {

// A write-only streambuf on a POSIX file descriptor. std::ofstream hides its descriptor, and we
// need one for fsync and for errno when a write fails (disk full, quota).
class FdStreambuf final : public std::streambuf {
public:
    explicit FdStreambuf(int fd) : fd_(fd) { setp(buffer_.data(), buffer_.data() + buffer_.size()); }
    FdStreambuf(const FdStreambuf&) = delete;
    FdStreambuf& operator=(const FdStreambuf&) = delete;

    // errno of the first failed write, 0 if none.
    int error() const { return error_; }

protected:
    int_type overflow(int_type ch) override {
        if (!drain()) return traits_type::eof();
        if (!traits_type::eq_int_type(ch, traits_type::eof())) {
            *pptr() = traits_type::to_char_type(ch);
            pbump(1);
        }
        return traits_type::not_eof(ch);
    }

    std::streamsize xsputn(const char* s, std::streamsize count) override {
        // Large blocks (matrix arrays) bypass the buffer: one copy fewer.
        if (count >= static_cast<std::streamsize>(buffer_.size())) {
            if (!drain() || !write_all(s, static_cast<std::size_t>(count))) return 0;
            return count;
        }
        return std::streambuf::xsputn(s, count);
    }

    int sync() override { return drain() ? 0 : -1; }

private:
    bool drain() {
        const std::size_t pending = static_cast<std::size_t>(pptr() - pbase());
        setp(buffer_.data(), buffer_.data() + buffer_.size());
        return write_all(buffer_.data(), pending);
    }

    bool write_all(const char* data, std::size_t size) {
        if (error_ != 0) return false;
        while (size > 0) {
            const ssize_t w = ::write(fd_, data, size);
            if (w < 0) {
                if (errno == EINTR) continue;
                error_ = errno;
                return false;
            }
            data += w;
            size -= static_cast<std::size_t>(w);
        }
        return true;
    }

    int fd_;
    int error_ = 0;
    std::array<char, 1 << 16> buffer_{};
};

[[noreturn]] void fail(const std::filesystem::path& path, const char* what, int err) {
    throw IoError(fmt::format("{}: {}: {}", path.string(), what, std::strerror(err)));
}

// Owns the temporary until it has been renamed: closes and unlinks it on every early exit.
class Temporary {
public:
    explicit Temporary(std::string name) : name_(std::move(name)) {}
    Temporary(const Temporary&) = delete;
    Temporary& operator=(const Temporary&) = delete;
    ~Temporary() {
        if (fd >= 0) ::close(fd);
        if (!committed) ::unlink(name_.c_str());
    }
    const std::string& name() const { return name_; }

    int fd = -1;
    bool committed = false;

private:
    std::string name_;
};

std::atomic<unsigned long long> g_counter{0};

}  // namespace

namespace {
// Writes straight into an existing file that rename cannot replace (a terminal, a pipe,
// /dev/stdout): there is no previous content to protect, and replacing the device node (or the
// /dev/stdout link) by a regular file would be wrong.
void write_in_place(const std::filesystem::path& path, const std::function<void(std::ostream&)>& writer) {
    const int fd = ::open(path.c_str(), O_WRONLY | O_CLOEXEC);
    if (fd < 0) fail(path, "cannot open for writing", errno);
    FdStreambuf buf(fd);
    std::ostream out(&buf);
    try {
        writer(out);
        out.flush();
    } catch (...) {
        ::close(fd);
        throw;
    }
    const int err = buf.error();
    const bool good = static_cast<bool>(out);
    if (::close(fd) != 0 && err == 0) fail(path, "close failed", errno);
    if (err != 0) fail(path, "write failed", err);
    if (!good) throw IoError(fmt::format("{}: write failed: the output stream reported an error", path.string()));
}
}  // namespace

void write_file_atomically(const std::filesystem::path& requested, const std::function<void(std::ostream&)>& writer) {
    std::error_code ec;
    const auto st = std::filesystem::status(requested, ec);  // follows links
    if (!ec && std::filesystem::exists(st) && !std::filesystem::is_regular_file(st) &&
        !std::filesystem::is_directory(st))
        return write_in_place(requested, writer);
    // A link is followed, so the link stays and the file it names is replaced.
    std::filesystem::path path = requested;
    if (std::filesystem::is_symlink(std::filesystem::symlink_status(requested, ec))) {
        const auto target = std::filesystem::canonical(requested, ec);
        if (!ec) path = target;
    }
    // Same directory as the destination, so that rename never crosses file systems.
    Temporary tmp(fmt::format("{}.tmp.{}.{}", path.string(), static_cast<long>(::getpid()), g_counter++));
    tmp.fd = ::open(tmp.name().c_str(), O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, 0666);
    if (tmp.fd < 0) {
        tmp.committed = true;  // nothing was created: nothing to unlink (and never someone else's file)
        fail(path, "cannot create file", errno);
    }

    FdStreambuf buf(tmp.fd);
    std::ostream out(&buf);
    writer(out);
    out.flush();
    if (buf.error() != 0) fail(path, "write failed", buf.error());
    if (!out) throw IoError(fmt::format("{}: write failed: the output stream reported an error", path.string()));

    // fsync before rename: otherwise a crash after the rename can leave an empty file in place
    // of both the old and the new content.
    if (::fsync(tmp.fd) != 0) fail(path, "fsync failed", errno);
    const int fd = tmp.fd;
    tmp.fd = -1;
    if (::close(fd) != 0) fail(path, "close failed", errno);
    if (std::rename(tmp.name().c_str(), path.c_str()) != 0) fail(path, "cannot replace file", errno);
    tmp.committed = true;
}

}  // namespace ffcube
