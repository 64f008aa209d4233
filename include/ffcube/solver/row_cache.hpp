// A bounded least-recently-used cache of form-factor rows, for re-shooting: in a closed scene a
// patch shoots many times, and recomputing its row (a hemicube) each time would dominate the solve.
#pragma once

#include <cstddef>
#include <cstdint>
#include <list>
#include <vector>

#include "ffcube/formfactor/sparse.hpp"

namespace ffcube {

class RowCache {
public:
    // Rows of patches 0..patches-1; at most capacity_bytes held (0: nothing is ever kept).
    RowCache(std::uint32_t patches, std::size_t capacity_bytes);

    // What a row costs against the bound: its non-zeros in double (12 bytes each) plus the node.
    static std::size_t cost(std::size_t nnz);

    // The row of patch i, now most recently used; nullptr when absent. The pointer stays valid
    // until the next insert().
    const SparseRow* find(std::uint32_t i);
    // Takes row i (absent before) as most recently used, evicting least recently used rows until
    // it fits. A row costing more than the capacity is not kept: returns false and leaves `row`
    // untouched; otherwise `row` is moved from.
    bool insert(std::uint32_t i, SparseRow& row);

    std::size_t bytes() const { return bytes_; }
    std::size_t peak_bytes() const { return peak_; }
    std::size_t capacity_bytes() const { return capacity_; }
    std::uint64_t evictions() const { return evictions_; }
    std::size_t rows() const { return lru_.size(); }

private:
    struct Entry {
        std::uint32_t patch;
        SparseRow row;
    };
    using List = std::list<Entry>;  // front: most recently used

    std::size_t capacity_;
    std::size_t bytes_ = 0;
    std::size_t peak_ = 0;
    std::uint64_t evictions_ = 0;
    List lru_;
    std::vector<List::iterator> where_;  // valid where present_[i]
    std::vector<bool> present_;
};

}  // namespace ffcube
