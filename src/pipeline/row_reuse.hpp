// Rows carried from one adaptive level to the next (pipeline/adaptive.hpp, docs/adaptive.md, "Rows
// reused between levels"). Internal to the pipeline layer.
//
// Refining splits some patches into elements in their own plane; nothing else moves. A patch p that
// was not split sees the same geometry from the same centre, so its new row is its old row, except
// that the column of each split patch j now belongs to j's elements c. That column is shared among
// them by reciprocity with the elements' own new rows, F_pc = F_pj · A_c F_cp / Σ_c' A_c' F_c'p (area
// shares when no element sees p), which keeps the row's sum and its total on j, and takes from the
// measured rows of the elements how much of p's energy each of them receives. Only the elements' rows
// are measured.
#pragma once

#include <cstdint>
#include <span>
#include <vector>

#include "ffcube/formfactor/row_provider.hpp"
#include "ffcube/scene/scene.hpp"

namespace ffcube {

// Every row a level handed out, by patch of that level's scene (empty: not asked).
struct LevelRows {
    std::vector<SparseRow> rows;
    std::vector<bool> present;
};

class ReusedRowProvider final : public RowProvider {
public:
    // inner measures the rows of `scene`; parent[e] is element e's patch in the previous level's
    // scene, split[p] > 1 marks the patches split; previous holds that level's rows (may be empty:
    // every row is measured). The references must outlive the provider.
    ReusedRowProvider(const Scene& scene, RowProvider& inner, std::span<const std::uint32_t> parent,
                      std::span<const std::uint32_t> split, LevelRows previous);
    std::uint32_t size() const override { return static_cast<std::uint32_t>(scene_.size()); }
    std::string name() const override { return inner_.name(); }
    void compute_rows(std::span<const std::uint32_t> rows, const RowSink& sink) override;

    // The rows handed out so far (for the next level).
    LevelRows take_rows() { return std::move(rows_); }
    std::uint64_t rows_measured() const { return measured_; }
    std::uint64_t rows_reused() const { return reused_; }

private:
    void measure_fresh();
    void reuse(std::uint32_t e);

    const Scene& scene_;
    RowProvider& inner_;
    std::vector<std::uint32_t> parent_;
    std::vector<std::uint32_t> split_;
    LevelRows previous_;
    std::vector<std::uint32_t> old_to_new_;     // unsplit old patch → its index now (or ~0u)
    std::vector<std::uint32_t> children_start_; // split old patch j → elements [start, start+count)
    std::vector<std::uint32_t> children_;
    LevelRows rows_;
    bool fresh_done_ = false;
    std::uint64_t measured_ = 0, reused_ = 0;
};

}  // namespace ffcube
