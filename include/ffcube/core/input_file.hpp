// Opening an input file the user named (a scene, a materials CSV, a matrix, an external glTF
// buffer): regular files only. A FIFO would block open() or read() forever, a device may never
// end (/dev/zero) or fail late, and a directory reads as an error far from its cause; each is
// refused up front with an InputError naming the path and what it is (docs/robustness.md,
// "Input paths").
//
// The path is checked with stat() before anything opens it, and the descriptor is checked again
// with fstat() after an O_NONBLOCK open (which cannot block even on a FIFO), so a path that is
// swapped for a FIFO between the two still cannot hang the reader.
#pragma once

#include <cstdint>
#include <filesystem>
#include <string>
#include <string_view>

namespace ffcube {

// "a directory", "a FIFO (named pipe)", "a character device", ... for messages; st_mode bits.
std::string file_type_name(unsigned mode);

// Throws InputError unless `path` (after symlinks) is a regular file:
//   PATH: cannot read ROLE: no such file                                 (missing)
//   PATH: is a directory, not KIND (only regular files are read)         (any other type)
// `kind` names what was expected ("an OBJ file", "a matrix file"), `role` the input ("the scene").
void require_regular_file(const std::filesystem::path& path, std::string_view kind, std::string_view role);

// An open, read-only descriptor of a regular file (closed with the object).
class InputFd {
public:
    InputFd() = default;
    explicit InputFd(int fd, std::uint64_t size) : fd_(fd), size_(size) {}
    InputFd(InputFd&& o) noexcept : fd_(o.fd_), size_(o.size_) { o.fd_ = -1; }
    InputFd& operator=(InputFd&& o) noexcept;
    InputFd(const InputFd&) = delete;
    InputFd& operator=(const InputFd&) = delete;
    ~InputFd();

    int get() const { return fd_; }
    int release() {
        const int fd = fd_;
        fd_ = -1;
        return fd;
    }
    std::uint64_t size() const { return size_; }  // st_size when opened

private:
    int fd_ = -1;
    std::uint64_t size_ = 0;
};

// require_regular_file, then open (O_RDONLY | O_NONBLOCK | O_CLOEXEC), fstat: still a regular
// file, then blocking mode back. InputError naming the path when it cannot be opened.
InputFd open_input_file(const std::filesystem::path& path, std::string_view kind, std::string_view role);

// The whole file, read through open_input_file. InputError naming the path on a read error.
std::string read_input_file(const std::filesystem::path& path, std::string_view kind, std::string_view role);

// A read-only mapping of a whole input file (for checks that look at every byte of a file that
// may be large without copying it); empty for an empty file.
class MappedInput {
public:
    MappedInput(const std::filesystem::path& path, std::string_view kind, std::string_view role);
    MappedInput(MappedInput&& o) noexcept : data_(o.data_), size_(o.size_) { o.data_ = nullptr, o.size_ = 0; }
    MappedInput(const MappedInput&) = delete;
    MappedInput& operator=(const MappedInput&) = delete;
    MappedInput& operator=(MappedInput&&) = delete;
    ~MappedInput();

    std::string_view bytes() const { return {static_cast<const char*>(data_), size_}; }

private:
    void* data_ = nullptr;
    std::size_t size_ = 0;
};

}  // namespace ffcube
