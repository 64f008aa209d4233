#include "ffcube/solver/row_cache.hpp"

#include <algorithm>
#include <utility>

#include "ffcube/core/error.hpp"

namespace ffcube {

RowCache::RowCache(std::uint32_t patches, std::size_t capacity_bytes)
    : capacity_(capacity_bytes), where_(patches), present_(patches, false) {}

std::size_t RowCache::cost(std::size_t nnz) {
    // A list node holds the entry and two pointers; the row's two vectors are counted by content.
    return nnz * (sizeof(std::uint32_t) + sizeof(double)) + sizeof(Entry) + 2 * sizeof(void*);
}

const SparseRow* RowCache::find(std::uint32_t i) {
    if (!present_[i]) return nullptr;
    lru_.splice(lru_.begin(), lru_, where_[i]);
    return &where_[i]->row;
}

bool RowCache::insert(std::uint32_t i, SparseRow& row) {
    FFCUBE_CHECK(!present_[i]);
    const std::size_t c = cost(row.nnz());
    if (c > capacity_) return false;
    while (bytes_ + c > capacity_) {
        Entry& victim = lru_.back();
        bytes_ -= cost(victim.row.nnz());
        present_[victim.patch] = false;
        lru_.pop_back();
        ++evictions_;
    }
    lru_.push_front(Entry{i, std::move(row)});
    where_[i] = lru_.begin();
    present_[i] = true;
    bytes_ += c;
    peak_ = std::max(peak_, bytes_);
    return true;
}

}  // namespace ffcube
