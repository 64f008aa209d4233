// Small helpers for tests that read single rows.
#pragma once

#include <cstdint>

#include "ffcube/formfactor/sparse.hpp"

namespace ffcube::test {

// Row r's value in column j (0 where j is not stored).
inline double entry(const SparseRow& r, std::uint32_t j) {
    for (std::size_t k = 0; k < r.col.size(); ++k)
        if (r.col[k] == j) return r.val[k];
    return 0.0;
}

}  // namespace ffcube::test
