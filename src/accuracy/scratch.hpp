// Internal to the accuracy layer. One job: the buffers one thread reuses across rows
// (NearFieldScratch), so that analysing and correcting a row allocates nothing once they have
// grown to the largest row.
#pragma once

#include <cstdint>
#include <utility>
#include <vector>

#include "accuracy/near_values.hpp"
#include "accuracy/row_merge.hpp"
#include "accuracy/shaft_test.hpp"
#include "ffcube/accuracy/near_field.hpp"

namespace ffcube {

struct NearFieldScratch::Buffers {
    // analyse
    std::vector<std::uint32_t> near;                        // candidates within reach
    accuracy::ShaftScratch shaft;                           // the occlusion test's
    accuracy::NearValueScratch values;                      // separated near values'
    std::vector<std::pair<std::uint32_t, double>> far;      // far entries, j increasing
    std::vector<std::uint32_t> cutting;                     // planes that cut the sender
    std::vector<Vec3> front;                                // the sender clipped to a receiver's front
    std::vector<std::pair<std::uint32_t, double>> near_exact;  // the near entries while merging
    std::vector<std::uint32_t> deferred;                    // auto exact visibility: refused pairs to try
    std::vector<std::uint32_t> blockers;                    // exact visibility: the shaft's candidates
    std::vector<std::vector<Vec3>> occluders;               // … their polygons
    std::vector<Vec3> sender;                               // … the sender clipped to j's front
    std::vector<std::vector<std::vector<Vec3>>> deferred_occluders;  // auto: each deferred pair's occluders
    std::vector<std::vector<Vec3>> deferred_sender;                  // … and its clipped sender
    std::vector<double> deferred_least;                              // … and its least cost
    int occluder_level = -1;  // the row's SenderVisibility::occluder_level once known, else -1
    // correct
    NearAnalysis analysis;  // when the caller has none
    std::vector<Vec3> quadrature_points;
    std::vector<double> quadrature_weights;
    accuracy::MergedRow merged;
    SparseRow inner;  // CorrectedRowProvider: the row as measured, kept for the range check's fallback
};

}  // namespace ffcube
