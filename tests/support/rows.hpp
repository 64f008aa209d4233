// Small helpers for tests that read single rows or build a matrix by hand.
#pragma once

#include <cstdint>
#include <vector>

#include "ffcube/formfactor/sparse.hpp"

namespace ffcube::test {

// Row r's value in column j (0 where j is not stored).
inline double entry(const SparseRow& r, std::uint32_t j) {
    for (std::size_t k = 0; k < r.col.size(); ++k)
        if (r.col[k] == j) return r.val[k];
    return 0.0;
}

// A dense matrix as a CsrMatrix (float values, zeros left out): exact for the float-representable
// values the hand-built form factors use.
inline CsrMatrix dense_to_csr(const std::vector<std::vector<double>>& f) {
    CsrMatrix m(static_cast<std::uint32_t>(f.size()));
    for (const auto& row : f) {
        std::vector<std::uint32_t> col;
        std::vector<float> val;
        for (std::uint32_t j = 0; j < row.size(); ++j)
            if (row[j] != 0.0) {
                col.push_back(j);
                val.push_back(static_cast<float>(row[j]));
            }
        m.append_row(col, val);
    }
    return m;
}

}  // namespace ffcube::test
