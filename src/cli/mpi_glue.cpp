#include "cli/mpi_glue.hpp"

#include <fmt/format.h>

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <string>
#include <thread>
#include <algorithm>

#include "ffcube/core/error.hpp"
#include "ffcube/core/log.hpp"
#include "ffcube/core/progress.hpp"
#include "ffcube/core/stats.hpp"
#include "ffcube/geometry/analytic.hpp"
#include "ffcube/io/transpose_scratch.hpp"
#include "ffcube/pipeline/enforcement.hpp"
#include "ffcube/pipeline/scene_loading.hpp"
#ifdef FFCUBE_HAVE_MPI
#include "ffcube/mpi/world.hpp"
#endif

namespace ffcube::cli {
namespace {

// The number of processes an MPI launcher started (0: not launched by one; 1 when only PMIx
// says so without a size).
unsigned long launched_size() {
    for (const char* name : {"OMPI_COMM_WORLD_SIZE", "PMI_SIZE"})
        if (const char* v = std::getenv(name)) return std::strtoul(v, nullptr, 10);
    return std::getenv("PMIX_RANK") ? 1 : 0;
}

void refuse_other_commands(std::string_view command) {
    if (launched_size() > 1 && command != "formfactors" && command != "solve")
        throw InputError(fmt::format("ffcube {} under mpirun with {} processes: only formfactors and solve are split "
                                     "over processes; run it as one process",
                                     command, launched_size()));
}

}  // namespace

#ifdef FFCUBE_HAVE_MPI

namespace {

// This rank's checkpoint: DIR holds one shard per rank, each a checkpoint of its own
// (io/checkpoint.hpp). Collective (a barrier after rank 0 made DIR).
std::optional<RowCheckpoint> open_shard(const CheckpointOptions& checkpoint, const Scene& scene,
                                        const FfmMetadata& meta, Report& report) {
    namespace fs = std::filesystem;
    const int r = mpi::rank(), k = mpi::size();
    const fs::path dir = checkpoint.dir;
    const fs::path shard = dir / fmt::format("rank-{}-of-{}", r, k);
    if (!checkpoint.resume && r == 0) {
        std::error_code ec;
        fs::create_directory(dir, ec);
        if (ec) throw IoError(fmt::format("--checkpoint {}: cannot create the directory: {}", dir.string(), ec.message()));
    }
    mpi::barrier();
    if (checkpoint.resume && !fs::exists(shard / "manifest.txt")) {
        std::string found;
        std::error_code ec;
        for (const auto& e : fs::directory_iterator(dir, ec))
            if (e.path().filename().string().starts_with("rank-")) found += " " + e.path().filename().string();
        throw InputError(fmt::format(
            "--checkpoint {} --resume: no shard {} for rank {} of {} (found:{}); resume with the number of ranks "
            "that made it",
            dir.string(), shard.filename().string(), r, k, found.empty() ? " none" : found));
    }
    CheckpointOptions mine_opts = checkpoint;
    mine_opts.dir = shard.string();
    return open_checkpoint(mine_opts, scene, meta, report);
}

// The rows of [first, last) missing from the store, each appended to it as it comes.
void compute_into(RowProvider& provider, RowCheckpoint& store, std::uint32_t first, std::uint32_t last,
                  bool progress) {
    std::vector<std::uint32_t> todo;
    for (std::uint32_t i = first; i < last; ++i)
        if (!store.has(i)) todo.push_back(i);
    info("rank 0: {} of its {} rows to compute", todo.size(), last - first);
    {
        Progress bar("rows (rank 0's block)", todo.size(), progress && mpi::rank() == 0);
        provider.compute_rows(todo, [&](std::uint32_t i, const SparseRow& row) {
            store.append(i, row);  // with its side figures
            bar.add();
        });
    }
    store.sync();
}

// Every other rank's statistics set handed to into_root on rank 0, one rank at a time in rank
// order (each travels in its flat form, core/stats.hpp). Collective: every rank has the same
// providers, so every rank calls this for the same sets.
template <class S, class F>
void merge_ranks_stats(const S& mine, F&& into_root) {
    const auto words = stats::to_words(mine);
    const std::vector<std::uint64_t> all = mpi::gather_to_root(words);
    if (all.empty()) return;  // not rank 0
    for (int r = 1; r < mpi::size(); ++r)
        into_root(stats::from_words<S>(std::span(all).subspan(std::size_t(r) * words.size(), words.size())));
}

// The statistics of every rank's rows (a process's providers saw only its own) merged into rank
// 0's providers, so its report and closure evidence count every row; returns that evidence (on
// rank 0; a rank's own elsewhere). The rows' own figures (obstructed shares, estimates) came with
// the rows. Collective.
ClosureEvidence merge_ranks_figures(const RowSource& rows) {
    if (HemicubeRowProvider* h = rows.hemicube())
        merge_ranks_stats(h->stats(), [&](const HemicubeStats& other) { h->merge_stats(other); });
    if (CorrectedRowProvider* c = rows.corrected())
        merge_ranks_stats(c->stats(), [&](const NearFieldStats& other) { c->merge_stats(other); });
    if (RaycastRowProvider* rc = rows.raycast())
        merge_ranks_stats(rc->stats(), [&](const RaycastStats& other) { rc->merge_stats(other); });
    // The analytic kernels' totals are the process's: every rank's added to rank 0's.
    merge_ranks_stats(analytic_stats(), [](const AnalyticStats& other) { merge_analytic_stats(other); });
    return closure_evidence(rows);
}

}  // namespace

void mpi_start(int& argc, char**& argv, std::string_view command) {
    if (launched_size() == 0) return;
    refuse_other_commands(command);
    mpi::start(argc, argv);
    if (mpi::rank() != 0) set_log_level(LogLevel::Quiet);  // one voice: rank 0's (warnings still print)
}

bool mpi_distributed() { return mpi::active(); }
bool mpi_root() { return !mpi::active() || mpi::rank() == 0; }
int mpi_finish(int code) { return mpi::finish(code); }

RowOptions mpi_row_options(RowOptions rows) {
    if (!mpi::active()) return rows;
    rows.worker_processes = false;
    if (rows.threads == 0) rows.threads = std::max(1u, std::thread::hardware_concurrency() / mpi::local_size());
    return rows;
}

Scene mpi_load_and_mesh(const SceneOptions& options, Report& report) {
    if (!mpi::active()) return load_and_mesh(options, report);
    std::optional<Scene> scene;
    if (mpi::rank() == 0) scene = load_and_mesh(options, report);
    Scene s = mpi::broadcast_scene(std::move(scene));
    report.set("mpi.ranks", mpi::size());
    return s;
}

namespace {

class MpiRowFeed final : public RowFeed {
public:
    MpiRowFeed(RowSource& rows, const Scene& scene, const RowOptions& options, const CheckpointOptions& checkpoint,
               const FfmMetadata& meta, const std::string& output, Report& report, bool progress)
        : rows_(rows), scene_(scene), options_(options), checkpoint_(checkpoint), meta_(meta), output_(output),
          report_(report), progress_(progress) {}
    void rows(const RowViewFn& sink) override;
    ClosureEvidence evidence() const override { return evidence_; }

private:
    RowSource& rows_;
    const Scene& scene_;
    RowOptions options_;
    CheckpointOptions checkpoint_;
    FfmMetadata meta_;
    std::string output_;
    Report& report_;
    bool progress_;
    ClosureEvidence evidence_;
};

void MpiRowFeed::rows(const RowViewFn& sink) {
    const Scene& scene = scene_;
    Report& report = report_;
    const bool progress = progress_;
    const CheckpointOptions& checkpoint = checkpoint_;
    const std::vector<std::uint32_t> bounds = mpi::row_blocks(scene, options_);
    const int r = mpi::rank(), k = mpi::size();
    const std::uint32_t first = bounds[r], last = bounds[r + 1];
    info("{} ranks; rank 0 computes rows {}..{} of {}, then takes the other blocks in order", k, bounds[0], bounds[1],
         scene.size());
    report.set("mpi.rows_rank0", bounds[1] - bounds[0]);
    report.set("mpi.streamed", true);
    RowProvider& provider = rows_.provider();
    // Where this rank's rows wait: its checkpoint shard, or (rank r > 0 without --checkpoint) a
    // spool, a checkpoint in a scratch directory in this node's temporary directory ($TMPDIR, else
    // /tmp: the output's directory may not exist on another node), removed on return and on error.
    std::optional<ScratchDir> spool_dir;
    std::optional<RowCheckpoint> store;
    if (!checkpoint.dir.empty()) {
        store = open_shard(checkpoint, scene, meta_, report);
    } else if (r != 0) {
        const std::filesystem::path name = std::filesystem::path(output_).filename();
        spool_dir.emplace(std::filesystem::temp_directory_path() / (name.empty() ? std::filesystem::path("ffcube") : name));
        store = RowCheckpoint::create(spool_dir->path() / "rows", checkpoint_manifest(scene, meta_));
    }
    if (store) {
        compute_into(provider, *store, first, last, progress);
        if (r == 0) {  // rank 0's block read back from its shard, bit-identical to the rows as computed
            mpi::RowBlock row;
            for (std::uint32_t i = first; i < last; ++i) {
                row.nnz.clear();
                row.col.clear();
                row.val.clear();
                row.side.clear();
                store->read_rows(i, i + 1, row.nnz, row.col, row.val, row.side);
                sink(i, RowView{row.col, row.val, row.side.front()});
            }
        }
    } else {  // rank 0 without a checkpoint: its rows straight to the sink
        std::vector<std::uint32_t> list;
        for (std::uint32_t i = first; i < last; ++i) list.push_back(i);
        Progress bar("rows (rank 0's block)", list.size(), progress);
        std::vector<float> val;
        provider.compute_rows(list, [&](std::uint32_t i, const SparseRow& row) {
            val.resize(row.val.size());
            for (std::size_t q = 0; q < val.size(); ++q) val[q] = static_cast<float>(row.val[q]);  // as CsrMatrix
            sink(i, RowView{row.col, val, row.side});
            bar.add();
        });
    }
    evidence_ = merge_ranks_figures(rows_);
    if (r != 0) {
        mpi::serve_rows(first, last, [&](std::uint32_t i, mpi::RowBlock& chunk) {
            store->read_rows(i, i + 1, chunk.nnz, chunk.col, chunk.val, chunk.side);
        });
        return;
    }
    std::uint64_t chunks = 0, largest = 0;
    for (int from = 1; from < k; ++from) {
        Progress bar(fmt::format("rows from rank {}", from), bounds[from + 1] - bounds[from], progress);
        const mpi::ReceivedRows got =
            mpi::receive_rows(from, bounds[from], bounds[from + 1], [&](std::uint32_t i, RowView row) {
                sink(i, row);
                bar.add();
            });
        chunks += got.chunks;
        largest = std::max(largest, got.largest_chunk_bytes);
    }
    report.set("mpi.chunks_received", chunks);
    report.set("mpi.largest_chunk_bytes", largest);
}

}  // namespace

std::unique_ptr<RowFeed> mpi_row_feed(RowSource& rows, const Scene& scene, const RowOptions& options,
                                      const CheckpointOptions& checkpoint, const FfmMetadata& meta,
                                      const std::string& output, Report& report, bool progress) {
    return std::make_unique<MpiRowFeed>(rows, scene, options, checkpoint, meta, output, report, progress);
}


std::unique_ptr<RowBlocks> mpi_row_blocks(const Scene& scene, const RowOptions& rows) {
    if (!mpi::active()) return nullptr;
    return std::make_unique<mpi::WorldRowBlocks>(mpi::row_blocks(scene, rows));
}

#else  // built without MPI

void mpi_start(int&, char**&, std::string_view) {
    if (launched_size() > 1)
        throw InputError(fmt::format("started by an MPI launcher as {} processes, but this ffcube was built without "
                                     "MPI (install libopenmpi-dev and rebuild; docs/scaling.md): each process would "
                                     "do all the work",
                                     launched_size()));
}
bool mpi_distributed() { return false; }
RowOptions mpi_row_options(RowOptions rows) { return rows; }
bool mpi_root() { return true; }
int mpi_finish(int code) { return code; }
Scene mpi_load_and_mesh(const SceneOptions& options, Report& report) { return load_and_mesh(options, report); }
std::unique_ptr<RowFeed> mpi_row_feed(RowSource&, const Scene&, const RowOptions&, const CheckpointOptions&,
                                      const FfmMetadata&, const std::string&, Report&, bool) {
    throw InternalError("mpi_row_feed without MPI");
}
std::unique_ptr<RowBlocks> mpi_row_blocks(const Scene&, const RowOptions&) { return nullptr; }

#endif

}  // namespace ffcube::cli
