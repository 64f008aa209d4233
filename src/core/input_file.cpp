#include "ffcube/core/input_file.hpp"

#include <fcntl.h>
#include <sys/mman.h>
#include <sys/stat.h>
#include <unistd.h>

#include <fmt/format.h>

#include <cerrno>
#include <cstring>

#include "ffcube/core/error.hpp"

namespace ffcube {

std::string file_type_name(unsigned mode) {
    switch (mode & S_IFMT) {
    case S_IFREG: return "a regular file";
    case S_IFDIR: return "a directory";
    case S_IFIFO: return "a FIFO (named pipe)";
    case S_IFCHR: return "a character device";
    case S_IFBLK: return "a block device";
    case S_IFSOCK: return "a socket";
    default: return "a special file";
    }
}

namespace {

[[noreturn]] void not_regular(const std::filesystem::path& path, unsigned mode, std::string_view kind) {
    throw InputError(fmt::format("{}: is {}, not {} (only regular files are read)", path.string(), file_type_name(mode), kind));
}

}  // namespace

void require_regular_file(const std::filesystem::path& path, std::string_view kind, std::string_view role) {
    struct stat st {};
    if (::stat(path.c_str(), &st) != 0) {
        const int err = errno;
        if (err == ENOENT || err == ENOTDIR) throw InputError(fmt::format("{}: cannot read {}: no such file", path.string(), role));
        throw InputError(fmt::format("{}: cannot read {}: {}", path.string(), role, std::strerror(err)));
    }
    if (!S_ISREG(st.st_mode)) not_regular(path, st.st_mode, kind);
}

InputFd& InputFd::operator=(InputFd&& o) noexcept {
    if (this != &o) {
        if (fd_ >= 0) ::close(fd_);
        fd_ = o.fd_;
        size_ = o.size_;
        o.fd_ = -1;
    }
    return *this;
}

InputFd::~InputFd() {
    if (fd_ >= 0) ::close(fd_);
}

InputFd open_input_file(const std::filesystem::path& path, std::string_view kind, std::string_view role) {
    require_regular_file(path, kind, role);
    // O_NONBLOCK: should the path have become a FIFO since the stat, open() returns at once
    // instead of waiting for a writer, and the fstat below refuses it.
    const int fd = ::open(path.c_str(), O_RDONLY | O_NONBLOCK | O_CLOEXEC);
    if (fd < 0) throw InputError(fmt::format("{}: cannot open {} for reading: {}", path.string(), role, std::strerror(errno)));
    InputFd out(fd, 0);
    struct stat st {};
    if (::fstat(fd, &st) != 0) throw InputError(fmt::format("{}: cannot read {}: {}", path.string(), role, std::strerror(errno)));
    if (!S_ISREG(st.st_mode)) not_regular(path, st.st_mode, kind);
    // Regular files ignore O_NONBLOCK for reads, but callers may hand the descriptor on.
    const int flags = ::fcntl(fd, F_GETFL);
    if (flags >= 0) ::fcntl(fd, F_SETFL, flags & ~O_NONBLOCK);
    return InputFd(out.release(), static_cast<std::uint64_t>(st.st_size));
}

std::string read_input_file(const std::filesystem::path& path, std::string_view kind, std::string_view role) {
    const InputFd fd = open_input_file(path, kind, role);
    std::string data;
    data.reserve(static_cast<std::size_t>(fd.size()));  // st_size of a regular file: what is there
    char buffer[1 << 16];
    for (;;) {
        const ssize_t n = ::read(fd.get(), buffer, sizeof buffer);
        if (n < 0 && errno == EINTR) continue;
        if (n < 0) throw InputError(fmt::format("{}: cannot read: {}", path.string(), std::strerror(errno)));
        if (n == 0) break;
        data.append(buffer, static_cast<std::size_t>(n));
    }
    return data;
}

MappedInput::MappedInput(const std::filesystem::path& path, std::string_view kind, std::string_view role) {
    const InputFd fd = open_input_file(path, kind, role);
    if (fd.size() == 0) return;
    if (fd.size() > std::uint64_t(SIZE_MAX)) throw InputError(fmt::format("{}: too large to map", path.string()));
    void* p = ::mmap(nullptr, static_cast<std::size_t>(fd.size()), PROT_READ, MAP_PRIVATE, fd.get(), 0);
    if (p == MAP_FAILED) throw InputError(fmt::format("{}: cannot read {}: {}", path.string(), role, std::strerror(errno)));
    data_ = p;
    size_ = static_cast<std::size_t>(fd.size());
}

MappedInput::~MappedInput() {
    if (data_ != nullptr) ::munmap(data_, size_);
}

}  // namespace ffcube
