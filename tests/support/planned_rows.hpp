// Every row of a scene from the hemicube provider, all under one plan (tests that compare two
// settings' rows bit for bit: occlusion culling, vertex upload).
#pragma once

#include <cstdint>
#include <numeric>
#include <vector>

#include "ffcube/gl/hemicube_provider.hpp"

namespace ffcube::test {

struct AllRows {
    std::vector<SparseRow> rows;  // by row index
    HemicubeStats stats;
};

inline AllRows all_rows(const Scene& s, const HemicubeOptions& o, RowProvider::RowPlan plan) {
    HemicubeRowProvider provider(s, o);
    std::vector<std::uint32_t> rows(s.size());
    std::iota(rows.begin(), rows.end(), 0u);
    const std::vector<RowProvider::RowPlan> plans(rows.size(), plan);
    AllRows r;
    r.rows.resize(s.size());
    provider.compute_rows_planned(rows, plans, [&](std::uint32_t i, const SparseRow& row) { r.rows[i] = row; });
    r.stats = provider.stats();
    return r;
}

}  // namespace ffcube::test
