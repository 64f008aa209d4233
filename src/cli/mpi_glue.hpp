// The commands' side of `mpirun -np K ffcube formfactors|solve …` (docs/scaling.md). Without an
// MPI launcher in the environment every function here is the one-process behaviour, and MPI is
// never initialised; the MPI layer (src/mpi) is only linked when CMake found MPI.
#pragma once

#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "cli/row_store.hpp"
#include "ffcube/accuracy/enforce.hpp"
#include "ffcube/formfactor/row_provider.hpp"
#include "ffcube/io/ffm.hpp"
#include "ffcube/io/report.hpp"
#include "ffcube/pipeline/options.hpp"
#include "ffcube/pipeline/row_source.hpp"
#include "ffcube/scene/scene.hpp"
#include "ffcube/solver/row_blocks.hpp"

namespace ffcube::cli {

// First thing in main(), before any thread: starts MPI when an MPI launcher started this process
// (OMPI_COMM_WORLD_SIZE, PMI_SIZE or PMIX_RANK in the environment). Throws InputError when
// launched as several processes by a build without MPI, or for a command other than formfactors
// and solve (each process would do all the work).
void mpi_start(int& argc, char**& argv, std::string_view command);
bool mpi_distributed();  // running under mpirun (even -np 1)
bool mpi_root();         // rank 0, or not distributed: the process that writes outputs
// The process's exit code; under mpirun a non-zero code aborts every rank (mpi::finish).
int mpi_finish(int code);

// The row options of this process. Under mpirun: hemicube workers are threads (OpenMPI and fork
// do not mix), and --threads 0 means this node's cores shared among its ranks.
RowOptions mpi_row_options(RowOptions rows);

// Distributed: rank 0 loads and meshes the scene and broadcasts it. Otherwise load_and_mesh.
Scene mpi_load_and_mesh(const SceneOptions& options, Report& report);


// What a RowSource keeps of the rows it made besides the rows, which under mpirun is each rank's
// own block only: reduced over the ranks onto rank 0.
struct RanksFigures {
    ClosureEvidence evidence;  // hemicube miss weight summed over the ranks, inner row sum min
    // With obstruction-only surfaces (Scene::drawn): every row's obstructed share
    // (RowSource::obstructed(), or a reused row's from its rank's checkpoint shard), each from the
    // rank that owns the row; empty without them.
    std::vector<double> obstructed;
};

// Every rank computes its block of rows (pipeline/row_partition.hpp), through its own shard of
// the checkpoint (DIR/rank-R-of-K) when one is given; rank 0 returns the whole matrix (and the
// ranks' figures in *figures), the other ranks nullopt. For the outputs that need the matrix in
// memory (.mtx, --ffm-version 1, View3D, Elmer); a .ffm streams (mpi_stream_rows).
std::optional<CsrMatrix> mpi_compute_matrix(RowSource& rows, const Scene& scene, const RowOptions& options,
                                            const CheckpointOptions& checkpoint, const FfmMetadata& meta,
                                            Report& report, bool progress, RanksFigures* figures);

// The streamed form of mpi_compute_matrix (docs/scaling.md, "Output"), in bounded memory on every
// rank: each rank computes its block into its checkpoint shard (DIR/rank-R-of-K) or, without
// --checkpoint, a spool in $TMPDIR named after `output` (a checkpoint of its own, removed at the
// end); rank 0 hands every row to sink in row order, as CsrMatrix's floats: its own block as
// computed (or read back from its shard), then each other rank's block in chunks it asks for one
// at a time (mpi::serve_rows). Rank 0 returns the figures; the other ranks return nullopt once rank 0 has
// every row of theirs (sink is never called there).
std::optional<RanksFigures> mpi_stream_rows(RowSource& rows, const Scene& scene, const RowOptions& options,
                                            const CheckpointOptions& checkpoint, const FfmMetadata& meta,
                                            const std::string& output, Report& report, bool progress,
                                            const std::function<void(std::uint32_t, RowView)>& sink);

// The solver's row blocks over the ranks (solver/row_blocks.hpp).
std::unique_ptr<RowBlocks> mpi_row_blocks(const Scene& scene, const RowOptions& rows);

}  // namespace ffcube::cli
