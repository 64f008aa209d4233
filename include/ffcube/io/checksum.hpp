// The 64-bit checksum of .ffm files (definition and a Python version in docs/ffm-format.md).
//
// Not a cryptographic hash: it detects accidental corruption. Each 8-byte little-endian word w
// updates the state by h = rotl64((h ^ w) * K, 27) with K odd, a bijection of h for fixed w and
// of w for fixed h, so any change confined to one word (every single-byte or single-bit error)
// always changes the result. It runs at several GB/s, well above disk speed.
#pragma once

#include <cstddef>
#include <cstdint>

namespace ffcube {

class Checksum64 {
public:
    // Feeds bytes; calls may split the input anywhere, the result depends only on the byte sequence.
    void update(const void* data, std::size_t size);
    // Checksum of all bytes fed so far (a trailing partial word counts zero-padded; the total
    // length is mixed in, so padding with zeros changes the result). Does not change the state.
    std::uint64_t value() const;

private:
    void word(std::uint64_t w);

    std::uint64_t h_ = 0xcbf29ce484222325ULL;
    std::uint64_t length_ = 0;
    unsigned char pending_[8] = {};
    std::size_t npending_ = 0;
};

// Checksum of one buffer.
std::uint64_t checksum64(const void* data, std::size_t size);

}  // namespace ffcube
