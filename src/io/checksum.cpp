#include "ffcube/io/checksum.hpp"

#include <bit>
#include <cstring>

namespace ffcube {
namespace {

static_assert(std::endian::native == std::endian::little,
              "the .ffm reader and writer copy little-endian words directly; port them with byte swaps first");

constexpr std::uint64_t kMul = 0x9E3779B97F4A7C15ULL;  // odd: multiplication by it is a bijection mod 2^64

std::uint64_t load_word(const unsigned char* p) {
    std::uint64_t w;
    std::memcpy(&w, p, 8);
    return w;
}

}  // namespace

void Checksum64::word(std::uint64_t w) { h_ = std::rotl((h_ ^ w) * kMul, 27); }

void Checksum64::update(const void* data, std::size_t size) {
    // An empty array's data() may be null, and memcpy from null is undefined even for 0 bytes
    // (found by tests/fuzz/fuzz_ffm.cpp on a matrix with no nonzeros).
    if (size == 0) return;
    const auto* p = static_cast<const unsigned char*>(data);
    length_ += size;
    if (npending_ > 0) {
        const std::size_t take = size < 8 - npending_ ? size : 8 - npending_;
        std::memcpy(pending_ + npending_, p, take);
        npending_ += take;
        p += take;
        size -= take;
        if (npending_ < 8) return;
        word(load_word(pending_));
        npending_ = 0;
    }
    for (; size >= 8; p += 8, size -= 8) word(load_word(p));
    std::memcpy(pending_, p, size);
    npending_ = size;
}

std::uint64_t Checksum64::value() const {
    Checksum64 c = *this;
    if (c.npending_ > 0) {
        std::memset(c.pending_ + c.npending_, 0, 8 - c.npending_);
        c.word(load_word(c.pending_));
    }
    // Murmur3's 64-bit finaliser: spreads every state bit over the whole result.
    std::uint64_t h = c.h_ ^ length_;
    h ^= h >> 33;
    h *= 0xff51afd7ed558ccdULL;
    h ^= h >> 33;
    h *= 0xc4ceb9fe1a85ec53ULL;
    h ^= h >> 33;
    return h;
}

std::uint64_t checksum64(const void* data, std::size_t size) {
    Checksum64 c;
    c.update(data, size);
    return c.value();
}

}  // namespace ffcube
