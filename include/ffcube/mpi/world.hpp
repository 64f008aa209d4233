// ffcube over MPI (docs/scaling.md). An optional layer, built when CMake finds MPI: a plain
// `ffcube` never initialises MPI; `mpirun -np K ffcube …` does, in main(), before any thread.
// Everything here is called from the main thread only (MPI_THREAD_FUNNELED).
#pragma once

#include <cstdint>
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

// Rank 0's scene (given there, nullopt elsewhere) on every rank, bit for bit (io/scene_blob.hpp).
Scene broadcast_scene(std::optional<Scene> scene);

// The row blocks of pipeline/row_partition.hpp, computed on rank 0 and broadcast: rank r owns
// rows [bounds[r], bounds[r+1]).
std::vector<std::uint32_t> row_blocks(const Scene& scene, const RowOptions& options);

// One rank's block of rows: nnz per row, then columns and values, rows in order.
struct RowBlock {
    std::vector<std::uint32_t> nnz, col;
    std::vector<float> val;
};
// Every rank's block, in rank order, into one n × n matrix on rank 0 (nullopt on the others).
std::optional<CsrMatrix> gather_rows(std::uint32_t n, std::span<const std::uint32_t> bounds, const RowBlock& mine);

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
