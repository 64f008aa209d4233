// Numbers as little-endian bytes, for every binary file and stream ffcube writes or reads (.ffm,
// checkpoints, PLY, View3D's binary output, the scene blob, the model wire). ffcube runs on
// little-endian hosts only, so a number's bytes are its memory; this is the one place that says so.
#pragma once

#include <bit>
#include <cstddef>
#include <cstring>
#include <ostream>
#include <type_traits>

namespace ffcube {

static_assert(std::endian::native == std::endian::little,
              "ffcube's binary files are little-endian and written from memory: port le_bytes.hpp with byte swaps first");

// v's bytes at p (p need not be aligned).
template <typename T>
    requires std::is_trivially_copyable_v<T>
void store_le(void* p, const T& v) {
    std::memcpy(p, &v, sizeof(T));
}

// The T whose bytes are at p (p need not be aligned).
template <typename T>
    requires std::is_trivially_copyable_v<T>
T load_le(const void* p) {
    T v;
    std::memcpy(&v, p, sizeof(T));
    return v;
}

// v's bytes appended to `out`: a std::ostream (write), or a byte container with append(first, last)
// (fmt::memory_buffer) or insert(end, first, last) (std::string, std::vector<char or std::uint8_t>).
template <typename Out, typename T>
    requires std::is_trivially_copyable_v<T>
void append_le(Out& out, const T& v) {
    char bytes[sizeof(T)];
    std::memcpy(bytes, &v, sizeof(T));
    if constexpr (std::is_base_of_v<std::ostream, Out>)
        out.write(bytes, sizeof(T));
    else if constexpr (requires { out.append(bytes, bytes + sizeof(T)); })
        out.append(bytes, bytes + sizeof(T));
    else
        out.insert(out.end(), bytes, bytes + sizeof(T));
}

}  // namespace ffcube
