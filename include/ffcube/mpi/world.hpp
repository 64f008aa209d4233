// ffcube over MPI (docs/scaling.md). An optional layer, built when CMake finds MPI: a plain
// `ffcube` never initialises MPI; `mpirun -np K ffcube …` does, in main(), before any thread.
// Everything here is called from the main thread only (MPI_THREAD_FUNNELED).
#pragma once

#include <cstddef>
#include <cstdint>
#include <functional>
#include <optional>
#include <span>
#include <vector>

#include "ffcube/formfactor/sparse.hpp"
#include "ffcube/pipeline/options.hpp"
#include "ffcube/scene/scene.hpp"
#include "ffcube/solver/row_blocks.hpp"

namespace ffcube::mpi {

// MPI_Init_thread; the EGL device preferred from then on is the local rank's
// (set_preferred_egl_device), so that the ranks on a GPU node drive different GPUs.
void start(int& argc, char**& argv);
bool active();  // start() was called and MPI_Finalize not yet
int rank();
int size();
unsigned local_rank();  // OMPI_COMM_WORLD_LOCAL_RANK, else the rank among the node's processes
unsigned local_size();  // ranks on this node (at least 1)
// The end of this process's part: code 0 finalises MPI and returns 0; any other code calls
// MPI_Abort(code), which ends every rank (one that just returned would leave the others waiting
// in a collective forever), and mpirun exits non-zero.
int finish(int code);
void barrier();

// Rank 0's scene (given there, nullopt elsewhere) on every rank, bit for bit (scene/scene_blob.hpp).
Scene broadcast_scene(std::optional<Scene> scene);

// The row blocks of pipeline/row_partition.hpp, computed on rank 0 and broadcast: rank r owns
// rows [bounds[r], bounds[r+1]).
std::vector<std::uint32_t> row_blocks(const Scene& scene, const RowOptions& options);

// One rank's block of rows: nnz per row, then columns and values, rows in order, and each row's
// side figures.
struct RowBlock {
    std::vector<std::uint32_t> nnz, col;
    std::vector<float> val;
    std::vector<RowSide> side;
};
// The streamed gather (docs/scaling.md, "Output"): rank 0 takes the blocks in rank order, one
// chunk of rows at a time, and asks for each chunk before the rank sends it, so rank 0 holds at
// most two chunks (the one it is using and the one arriving), whatever the matrix's size; a rank
// that is ahead keeps its rows where it computed them (its checkpoint shard or a spool file) until
// asked. A chunk is whole rows, about kRowChunkBytes of columns and values (at least one row).
inline constexpr std::size_t kRowChunkBytes = std::size_t{8} << 20;
// On rank r > 0: sends rows [first, last) of its block, read_row(i, chunk) appending row i to a
// chunk (nnz, columns, values, side), as rank 0 asks for them; returns when every row was sent.
void serve_rows(std::uint32_t first, std::uint32_t last,
                const std::function<void(std::uint32_t, RowBlock&)>& read_row);
// On rank 0: the rows [first, last) that rank `from` serves, each handed to sink in order (the
// float values as sent: what the rank's checkpoint or CsrMatrix holds).
struct ReceivedRows {
    std::uint64_t chunks = 0;
    std::uint64_t largest_chunk_bytes = 0;  // u32 nnz and 4 f64 side figures per row, u32 column and float value per entry
};
ReceivedRows receive_rows(int from, std::uint32_t first, std::uint32_t last,
                          const std::function<void(std::uint32_t, RowView)>& sink);
// v summed (or its minimum taken) over the ranks, element by element, onto rank 0 (MPI_Reduce;
// the other ranks' v is left as it was). Collective.
void reduce_sum_to_root(std::span<double> v);
void reduce_min_to_root(std::span<double> v);
// Every rank's `mine` (the same length on every rank) on rank 0, one after another in rank order
// (MPI_Gather); empty on the other ranks. Collective. For the flat form of statistics sets
// (core/stats.hpp), which rank 0 merges in rank order.
std::vector<std::uint64_t> gather_to_root(std::span<const std::uint64_t> mine);

// RowBlocks (solver/row_blocks.hpp) over MPI_COMM_WORLD: share is an in-place MPI_Allgatherv,
// sum gathers every rank's partial values and adds them in rank order (the same bits on every
// rank, whatever the MPI library's reduction order), max is MPI_Allreduce(MAX).
class WorldRowBlocks final : public RowBlocks {
public:
    explicit WorldRowBlocks(std::vector<std::uint32_t> bounds);
    std::uint32_t first() const override;
    std::uint32_t last() const override;
    void share(std::span<double> x) override;
    void sum(std::span<double> v) override;
    void max(std::span<double> v) override;

private:
    std::vector<std::uint32_t> bounds_;
    std::vector<int> counts_, displs_;
    std::vector<double> gathered_;
};

}  // namespace ffcube::mpi
