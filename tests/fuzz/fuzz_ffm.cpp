// libFuzzer target: the .ffm reader (versions 1 and 2) on arbitrary bytes.
// The first input byte chooses a mode: odd = take the rest as it is (exercises the header, size
// and checksum checks); 0 mod 4 = also overwrite version 1's trailing checksum with the right one;
// 2 mod 4 = recompute version 2's checksums (head, every block, trailer), so the structural
// validation behind the checksums (row_ptr, columns, values, areas, objects, names; version 2's
// block headers, zstd frames, varints and value planes) is reached too, which random bytes would
// otherwise never pass. The bytes are handed to read_ffm
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

std::uint64_t word(const std::vector<std::uint8_t>& b, std::size_t at) {
    std::uint64_t v = 0;
    std::memcpy(&v, b.data() + at, 8);
    return v;
}
void set_word(std::vector<std::uint8_t>& b, std::size_t at, std::uint64_t v) { std::memcpy(b.data() + at, &v, 8); }

// Version 2's checksums made right, walking the file as docs/ffm-format.md lays it out (as far
// as the bytes allow: a walk that leaves the file stops).
void reseal_v2(std::vector<std::uint8_t>& b) {
    if (b.size() < 64 + 32) return;
    std::uint32_t n = 0, len = 0;
    std::memcpy(&n, b.data() + 12, 4);
    std::uint64_t text = 0;
    for (std::size_t off : {48, 52, 56, 60}) {
        std::memcpy(&len, b.data() + off, 4);
        text += len;
    }
    const auto pad8 = [](std::uint64_t x) { return (x + 7) / 8 * 8; };
    const std::uint64_t head = 64 + pad8(text) + 8 * std::uint64_t(n) + pad8(4 * std::uint64_t(n)) + 8;
    const std::size_t trailer = b.size() - 32;
    if (head > trailer) return;
    ffcube::Checksum64 chain;
    const std::uint64_t h = ffcube::checksum64(b.data(), head - 8);
    set_word(b, head - 8, h);
    chain.update(&h, 8);
    std::uint64_t p = head;
    while (p + 48 <= trailer) {
        const std::uint64_t stored = word(b, p + 32);
        if (stored > trailer - p - 48 || pad8(stored) > trailer - p - 48) return;
        ffcube::Checksum64 s;
        s.update(b.data() + p, 40);
        s.update(b.data() + p + 48, pad8(stored));
        const std::uint64_t c = s.value();
        set_word(b, p + 40, c);
        chain.update(&c, 8);
        p += 48 + pad8(stored);
    }
    chain.update(b.data() + trailer, 16);
    set_word(b, trailer + 16, chain.value());
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    if (size == 0) return 0;
    std::vector<std::uint8_t> bytes(data + 1, data + size);
    if (data[0] % 4 == 2) {
        reseal_v2(bytes);
    } else if (data[0] % 2 == 0 && bytes.size() >= 8) {
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
