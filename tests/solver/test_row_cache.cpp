#include <gtest/gtest.h>

#include "ffcube/solver/row_cache.hpp"

namespace ffcube {
namespace {

SparseRow row_of(std::uint32_t nnz, double value) {
    SparseRow r;
    for (std::uint32_t k = 0; k < nnz; ++k) {
        r.col.push_back(k);
        r.val.push_back(value);
    }
    return r;
}

TEST(RowCache, LeastRecentlyUsedIsEvicted) {
    // Room for exactly three rows of 4 non-zeros (and not four).
    RowCache cache(10, 3 * RowCache::cost(4) + RowCache::cost(4) / 2);
    for (std::uint32_t i = 0; i < 3; ++i) {
        SparseRow r = row_of(4, i);
        ASSERT_TRUE(cache.insert(i, r));
        EXPECT_TRUE(r.col.empty());  // moved into the cache
    }
    EXPECT_EQ(cache.bytes(), 3 * RowCache::cost(4));
    ASSERT_NE(cache.find(0), nullptr);  // 0 is now the most recent; 1 the least
    SparseRow r3 = row_of(4, 3);
    ASSERT_TRUE(cache.insert(3, r3));
    EXPECT_EQ(cache.evictions(), 1u);
    EXPECT_EQ(cache.find(1), nullptr);
    ASSERT_NE(cache.find(0), nullptr);
    EXPECT_EQ(cache.find(0)->val[0], 0.0);
    ASSERT_NE(cache.find(2), nullptr);
    ASSERT_NE(cache.find(3), nullptr);
    EXPECT_EQ(cache.find(3)->val[0], 3.0);
    EXPECT_EQ(cache.rows(), 3u);
    EXPECT_EQ(cache.peak_bytes(), 3 * RowCache::cost(4));
}

TEST(RowCache, BigRowEvictsSeveral) {
    RowCache cache(10, 3 * RowCache::cost(4));
    for (std::uint32_t i = 0; i < 3; ++i) {
        SparseRow r = row_of(4, i);
        cache.insert(i, r);
    }
    // The big row fits beside ⌊(capacity − cost(12)) / cost(4)⌋ of the small ones; the others go,
    // least recently used first.
    SparseRow big = row_of(12, 9);
    ASSERT_TRUE(cache.insert(5, big));
    EXPECT_EQ(cache.evictions(), 3u - (3 * RowCache::cost(4) - RowCache::cost(12)) / RowCache::cost(4));
    EXPECT_LE(cache.bytes(), cache.capacity_bytes());
    EXPECT_NE(cache.find(5), nullptr);
}

TEST(RowCache, OversizeAndZeroCapacityKeepNothing) {
    RowCache none(4, 0);
    SparseRow r = row_of(1, 1);
    EXPECT_FALSE(none.insert(0, r));
    EXPECT_EQ(r.nnz(), 1u);  // untouched
    EXPECT_EQ(none.find(0), nullptr);

    RowCache small(4, RowCache::cost(2));
    SparseRow big = row_of(3, 1);
    EXPECT_FALSE(small.insert(1, big));
    EXPECT_EQ(small.evictions(), 0u);
    EXPECT_EQ(small.bytes(), 0u);
}

}  // namespace
}  // namespace ffcube
