// Runs of equal item IDs in a line of the hemicube's item buffer (the rows' accumulation,
// gl/hemicube_worker.cpp): a patch covers runs of neighbouring pixels, and finding where each run
// starts with one compare a pixel, four or eight pixels at a time, replaces a loop whose exit branch
// mispredicted at every run's end (docs/benchmarks.md, "The rows' accumulation").
#pragma once

#include <bit>
#include <cstddef>
#include <cstdint>
#include <span>

#if defined(__SSE2__)
#include <emmintrin.h>
#endif
#if defined(__x86_64__)
#include <immintrin.h>
#endif

namespace ffcube {

namespace runs_detail {

// mark_run_starts on SSE2: four pixels at a time.
inline void mark_run_starts_sse2(std::span<const std::uint32_t> ids, std::uint64_t* bits) {
    const std::size_t n = ids.size();
    const std::uint32_t* d = ids.data();
    for (std::size_t w = 0; w * 64 < n; ++w) {
        const std::size_t lo = w * 64, hi = lo + 64 < n ? lo + 64 : n;
        std::uint64_t word = 0;
        std::size_t k = lo;
        if (k == 0) {  // pixel 0 starts a run; pixels 1..3 compared one by one (no d[-1])
            word = 1;
            for (k = 1; k < 4 && k < hi; ++k) word |= static_cast<std::uint64_t>(d[k] != d[k - 1]) << k;
        }
#if defined(__SSE2__)
        for (; k + 4 <= hi; k += 4) {
            const __m128i a = _mm_loadu_si128(reinterpret_cast<const __m128i*>(d + k));
            const __m128i b = _mm_loadu_si128(reinterpret_cast<const __m128i*>(d + k - 1));
            const auto same = static_cast<unsigned>(_mm_movemask_ps(_mm_castsi128_ps(_mm_cmpeq_epi32(a, b))));
            word |= static_cast<std::uint64_t>(~same & 0xFu) << (k - lo);
        }
#endif
        for (; k < hi; ++k) word |= static_cast<std::uint64_t>(d[k] != d[k - 1]) << (k - lo);
        bits[w] = word;
    }
}

#if defined(__x86_64__)
// The same on AVX2, eight pixels at a time (the same bits: a compare per pixel either way). Its
// own copy of the word loop: a template shared with the SSE2 one would need this body inlined
// into it across the target attribute, which GCC does not do.
__attribute__((target("avx2"))) inline void mark_run_starts_avx2(std::span<const std::uint32_t> ids, std::uint64_t* bits) {
    const std::size_t n = ids.size();
    const std::uint32_t* d = ids.data();
    for (std::size_t w = 0; w * 64 < n; ++w) {
        const std::size_t lo = w * 64, hi = lo + 64 < n ? lo + 64 : n;
        std::uint64_t word = 0;
        std::size_t k = lo;
        if (k == 0) {  // pixel 0 starts a run; pixels 1..7 compared one by one (no d[-1])
            word = 1;
            for (k = 1; k < 8 && k < hi; ++k) word |= static_cast<std::uint64_t>(d[k] != d[k - 1]) << k;
        }
        for (; k + 8 <= hi; k += 8) {
            const __m256i a = _mm256_loadu_si256(reinterpret_cast<const __m256i*>(d + k));
            const __m256i b = _mm256_loadu_si256(reinterpret_cast<const __m256i*>(d + k - 1));
            const auto same = static_cast<unsigned>(_mm256_movemask_ps(_mm256_castsi256_ps(_mm256_cmpeq_epi32(a, b))));
            word |= static_cast<std::uint64_t>(~same & 0xFFu) << (k - lo);
        }
        for (; k < hi; ++k) word |= static_cast<std::uint64_t>(d[k] != d[k - 1]) << (k - lo);
        bits[w] = word;
    }
}
#endif

}  // namespace runs_detail

// Sets bit k of bits (bits[k / 64] >> k % 64) where a run starts: k = 0, or ids[k] ≠ ids[k − 1];
// clears the others. bits holds (ids.size() + 63) / 64 words. Eight pixels at a time where the
// CPU has AVX2 (checked once), else four.
inline void mark_run_starts(std::span<const std::uint32_t> ids, std::uint64_t* bits) {
#if defined(__x86_64__)
    static const bool avx2 = __builtin_cpu_supports("avx2");
    if (avx2) return runs_detail::mark_run_starts_avx2(ids, bits);
#endif
    runs_detail::mark_run_starts_sse2(ids, bits);
}

// Calls f(a, b) for each run [a, b) of the line of n pixels whose starts mark_run_starts set.
template <class F>
inline void for_each_run(const std::uint64_t* bits, std::size_t n, F&& f) {
    std::size_t a = 0;
    bool open = false;
    for (std::size_t w = 0; w < (n + 63) / 64; ++w) {
        for (std::uint64_t m = bits[w]; m != 0; m &= m - 1) {
            const std::size_t k = w * 64 + static_cast<std::size_t>(std::countr_zero(m));
            if (open) f(a, k);
            a = k;
            open = true;
        }
    }
    if (open) f(a, n);
}

}  // namespace ffcube
