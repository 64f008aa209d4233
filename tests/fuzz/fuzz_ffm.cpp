// libFuzzer target: the .ffm reader on arbitrary bytes.
// The first input byte chooses a mode: odd = take the rest as it is (exercises the header, size
// and checksum checks); even = also overwrite the trailing checksum with the right one, so the
// structural validation behind the checksum (row_ptr, columns, values, areas, objects, names) is
// reached too, which random bytes would otherwise never pass. The bytes are handed to read_ffm
// through a memory file (memfd), so no disk is involved.
#include <sys/mman.h>
#include <unistd.h>

#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <string>
#include <vector>

#include "ffcube/core/error.hpp"
#include "ffcube/io/checksum.hpp"
#include "ffcube/io/ffm.hpp"

namespace {

int memory_file() {
    static const int fd = [] {
        const int f = memfd_create("fuzz.ffm", MFD_CLOEXEC);
        if (f < 0) std::abort();
        return f;
    }();
    return fd;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    if (size == 0) return 0;
    std::vector<std::uint8_t> bytes(data + 1, data + size);
    if (data[0] % 2 == 0 && bytes.size() >= 8) {
        const std::uint64_t sum = ffcube::checksum64(bytes.data(), bytes.size() - 8);
        std::memcpy(bytes.data() + bytes.size() - 8, &sum, 8);
    }
    const int fd = memory_file();
    if (ftruncate(fd, 0) != 0 || pwrite(fd, bytes.data(), bytes.size(), 0) != static_cast<ssize_t>(bytes.size()))
        std::abort();
    try {
        const ffcube::FfmFile f = ffcube::read_ffm("/proc/self/fd/" + std::to_string(fd));
        // A file that passed validation must be safe to index as documented.
        for (std::uint32_t i = 0; i < f.matrix.size(); ++i) {
            const ffcube::RowView row = f.matrix.row(i);
            for (std::uint32_t c : row.col)
                if (c >= f.matrix.size()) std::abort();
            if (f.objects[i] >= f.object_names.size()) std::abort();
        }
    } catch (const ffcube::InputError&) {
        // refused with a message: the expected outcome for bad input
    }
    return 0;
}
