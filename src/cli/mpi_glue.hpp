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

#include "ffcube/accuracy/enforce.hpp"
#include "ffcube/formfactor/row_provider.hpp"
#include "ffcube/io/ffm.hpp"
#include "ffcube/io/report.hpp"
#include "ffcube/pipeline/form_factors.hpp"
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


// The rows of every rank, as a RowFeed (pipeline/form_factors.hpp; docs/scaling.md, "Output"), in
// bounded memory on every rank: each rank computes its block (pipeline/row_partition.hpp) into its
// checkpoint shard (DIR/rank-R-of-K) or, without --checkpoint, a spool in $TMPDIR named after
// `output` (a checkpoint of its own, removed at the end); on rank 0 rows() hands every row to the
// sink in row order: its own block as computed (or read back from its shard), then each other
// rank's block in chunks it asks for one at a time (mpi::serve_rows). On the other ranks rows()
// returns once rank 0 has every row of theirs (the sink is never called there). Collective. Each
// row comes with its side figures (from the rank that made it); the closure evidence is every
// rank's, merged onto rank 0.
std::unique_ptr<RowFeed> mpi_row_feed(RowSource& rows, const Scene& scene, const RowOptions& options,
                                      const CheckpointOptions& checkpoint, const FfmMetadata& meta,
                                      const std::string& output, Report& report, bool progress);

// The solver's row blocks over the ranks (solver/row_blocks.hpp).
std::unique_ptr<RowBlocks> mpi_row_blocks(const Scene& scene, const RowOptions& rows);

}  // namespace ffcube::cli
