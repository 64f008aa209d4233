#include "ffcube/io/atomic_file.hpp"

#include <fcntl.h>
#include <fmt/format.h>
#include <unistd.h>

#include <array>
#include <atomic>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <memory>
#include <optional>
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


struct AtomicFile::Impl {
    std::filesystem::path path;               // the file that will be replaced (a link followed)
    std::optional<Temporary> tmp;             // absent when writing in place
    int in_place_fd = -1;
    std::optional<FdStreambuf> buf;
    std::optional<std::ostream> out;
    bool done = false;

    ~Impl() {
        out.reset();
        buf.reset();
        if (in_place_fd >= 0) ::close(in_place_fd);
    }
};

AtomicFile::AtomicFile(const std::filesystem::path& requested) : impl_(std::make_unique<Impl>()) {
    std::error_code ec;
    const auto st = std::filesystem::status(requested, ec);  // follows links
    if (!ec && std::filesystem::exists(st) && !std::filesystem::is_regular_file(st) &&
        !std::filesystem::is_directory(st)) {
        // Straight into an existing file that rename cannot replace (a terminal, a pipe,
        // /dev/stdout): there is no previous content to protect, and replacing the device node
        // (or the /dev/stdout link) by a regular file would be wrong.
        impl_->path = requested;
        impl_->in_place_fd = ::open(requested.c_str(), O_WRONLY | O_CLOEXEC);
        if (impl_->in_place_fd < 0) fail(requested, "cannot open for writing", errno);
        impl_->buf.emplace(impl_->in_place_fd);
    } else {
        // A link is followed, so the link stays and the file it names is replaced.
        impl_->path = requested;
        if (std::filesystem::is_symlink(std::filesystem::symlink_status(requested, ec))) {
            const auto target = std::filesystem::canonical(requested, ec);
            if (!ec) impl_->path = target;
        }
        // Same directory as the destination, so that rename never crosses file systems.
        Temporary& tmp = impl_->tmp.emplace(
            fmt::format("{}.tmp.{}.{}", impl_->path.string(), static_cast<long>(::getpid()), g_counter++));
        tmp.fd = ::open(tmp.name().c_str(), O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, 0666);
        if (tmp.fd < 0) {
            tmp.committed = true;  // nothing was created: nothing to unlink (and never someone else's file)
            fail(impl_->path, "cannot create file", errno);
        }
        impl_->buf.emplace(tmp.fd);
    }
    impl_->out.emplace(&*impl_->buf);
}

AtomicFile::~AtomicFile() = default;

std::ostream& AtomicFile::stream() { return *impl_->out; }

void AtomicFile::check() {
    if (impl_->buf->error() != 0) fail(impl_->path, "write failed", impl_->buf->error());
    if (!*impl_->out)
        throw IoError(fmt::format("{}: write failed: the output stream reported an error", impl_->path.string()));
}

void AtomicFile::commit() {
    FFCUBE_CHECK_MSG(!impl_->done, "AtomicFile committed twice");
    impl_->done = true;
    std::ostream& out = *impl_->out;
    out.flush();
    check();
    if (!impl_->tmp) {
        const int fd = impl_->in_place_fd;
        impl_->in_place_fd = -1;
        if (::close(fd) != 0) fail(impl_->path, "close failed", errno);
        return;
    }
    Temporary& tmp = *impl_->tmp;
    // fsync before rename: otherwise a crash after the rename can leave an empty file in place
    // of both the old and the new content.
    if (::fsync(tmp.fd) != 0) fail(impl_->path, "fsync failed", errno);
    const int fd = tmp.fd;
    tmp.fd = -1;
    if (::close(fd) != 0) fail(impl_->path, "close failed", errno);
    if (std::rename(tmp.name().c_str(), impl_->path.c_str()) != 0) fail(impl_->path, "cannot replace file", errno);
    tmp.committed = true;
}

void write_file_atomically(const std::filesystem::path& requested, const std::function<void(std::ostream&)>& writer) {
    AtomicFile file(requested);
    writer(file.stream());
    file.commit();
}

}  // namespace ffcube
