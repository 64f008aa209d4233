#include "ffcube/mpi/world.hpp"

#include <mpi.h>
#include <fmt/format.h>

#include <algorithm>
#include <climits>
#include <cstdlib>
#include <string>

#include "ffcube/core/error.hpp"
#include "ffcube/gl/context.hpp"
#include "ffcube/scene/scene_blob.hpp"
#include "ffcube/pipeline/row_partition.hpp"

namespace ffcube::mpi {
namespace {

bool g_active = false;
int g_rank = 0, g_size = 1;
unsigned g_local = 0, g_local_size = 1;

// Largest count of one MPI call: counts are ints.
constexpr std::size_t kChunk = std::size_t{1} << 28;

void check(int rc, const char* what) {
    if (rc != MPI_SUCCESS) throw IoError(fmt::format("MPI: {} failed (error {})", what, rc));
}

template <class T>
MPI_Datatype type_of() {
    if constexpr (sizeof(T) == 1) return MPI_BYTE;
    else if constexpr (std::is_same_v<T, float>) return MPI_FLOAT;
    else if constexpr (std::is_same_v<T, double>) return MPI_DOUBLE;
    else if constexpr (sizeof(T) == 4) return MPI_UINT32_T;
    else return MPI_UINT64_T;
}

template <class T>
void send_all(std::span<const T> data, int to, int tag) {
    for (std::size_t at = 0; at < data.size() || at == 0; at += kChunk) {
        const std::size_t n = std::min(kChunk, data.size() - at);
        check(MPI_Send(data.data() + at, static_cast<int>(n), type_of<T>(), to, tag, MPI_COMM_WORLD), "MPI_Send");
        if (data.empty()) break;
    }
}

template <class T>
void recv_all(std::span<T> data, int from, int tag) {
    for (std::size_t at = 0; at < data.size() || at == 0; at += kChunk) {
        const std::size_t n = std::min(kChunk, data.size() - at);
        check(MPI_Recv(data.data() + at, static_cast<int>(n), type_of<T>(), from, tag, MPI_COMM_WORLD,
                       MPI_STATUS_IGNORE),
              "MPI_Recv");
        if (data.empty()) break;
    }
}

template <class T>
void broadcast_vector(std::vector<T>& v) {
    std::uint64_t n = v.size();
    check(MPI_Bcast(&n, 1, MPI_UINT64_T, 0, MPI_COMM_WORLD), "MPI_Bcast");
    v.resize(n);
    for (std::size_t at = 0; at < n; at += kChunk)
        check(MPI_Bcast(v.data() + at, static_cast<int>(std::min<std::size_t>(kChunk, n - at)), type_of<T>(), 0,
                        MPI_COMM_WORLD),
              "MPI_Bcast");
}

}  // namespace

void start(int& argc, char**& argv) {
    int provided = 0;
    check(MPI_Init_thread(&argc, &argv, MPI_THREAD_FUNNELED, &provided), "MPI_Init_thread");
    g_active = true;
    MPI_Comm_rank(MPI_COMM_WORLD, &g_rank);
    MPI_Comm_size(MPI_COMM_WORLD, &g_size);
    // The ranks sharing this node (collective: every rank makes the call).
    MPI_Comm node;
    check(MPI_Comm_split_type(MPI_COMM_WORLD, MPI_COMM_TYPE_SHARED, g_rank, MPI_INFO_NULL, &node),
          "MPI_Comm_split_type");
    int r = 0, s = 1;
    MPI_Comm_rank(node, &r);
    MPI_Comm_size(node, &s);
    MPI_Comm_free(&node);
    g_local = static_cast<unsigned>(r);
    g_local_size = static_cast<unsigned>(std::max(1, s));
    if (const char* local = std::getenv("OMPI_COMM_WORLD_LOCAL_RANK"))
        g_local = static_cast<unsigned>(std::strtoul(local, nullptr, 10));
    set_preferred_egl_device(g_local);
}

bool active() { return g_active; }
int rank() { return g_rank; }
int size() { return g_size; }
unsigned local_rank() { return g_local; }
unsigned local_size() { return g_local_size; }

int finish(int code) {
    if (!g_active) return code;
    if (code != 0) {
        std::fflush(nullptr);
        MPI_Abort(MPI_COMM_WORLD, code);
    }
    g_active = false;
    MPI_Finalize();
    return 0;
}

void barrier() { check(MPI_Barrier(MPI_COMM_WORLD), "MPI_Barrier"); }

Scene broadcast_scene(std::optional<Scene> scene) {
    std::vector<std::uint8_t> bytes;
    if (g_rank == 0) {
        FFCUBE_CHECK(scene.has_value());
        bytes = serialize_scene(*scene);
    }
    broadcast_vector(bytes);
    if (g_rank == 0) return std::move(*scene);
    return deserialize_scene(bytes);
}

std::vector<std::uint32_t> row_blocks(const Scene& scene, const RowOptions& options) {
    std::vector<std::uint32_t> bounds;
    if (g_rank == 0) bounds = balanced_row_blocks(estimate_row_costs(scene, options), static_cast<unsigned>(g_size));
    broadcast_vector(bounds);
    FFCUBE_CHECK(bounds.size() == std::size_t(g_size) + 1);
    return bounds;
}

namespace {
constexpr int kTagAsk = 21, kTagChunk = 22, kTagChunkNnz = 23, kTagChunkCol = 24, kTagChunkVal = 25, kTagChunkSide = 26;

// A chunk's side figures on the wire: four doubles a row (obstructed share, error,
// tolerance_error, measure), each exact in a double (a float and a small integer; NaN stays NaN).
constexpr std::size_t kSideWords = 4;
void pack_sides(std::span<const RowSide> side, std::vector<double>& out) {
    out.clear();
    for (const RowSide& s : side) out.insert(out.end(), {s.obstructed, s.error, s.tolerance_error, double(s.measure)});
}
RowSide unpack_side(const double* w) {
    RowSide s;
    s.obstructed = w[0];
    s.error = static_cast<float>(w[1]);
    s.tolerance_error = static_cast<float>(w[2]);
    s.measure = static_cast<std::int8_t>(w[3]);
    return s;
}
}  // namespace

void serve_rows(std::uint32_t first, std::uint32_t last,
                const std::function<void(std::uint32_t, RowBlock&)>& read_row) {
    RowBlock chunk;
    std::vector<double> sides;
    for (std::uint32_t i = first; i < last;) {
        std::uint32_t ask = 0;
        check(MPI_Recv(&ask, 1, MPI_UINT32_T, 0, kTagAsk, MPI_COMM_WORLD, MPI_STATUS_IGNORE), "MPI_Recv");
        FFCUBE_CHECK(ask == i);  // rank 0 asks for the rows in order
        chunk.nnz.clear();
        chunk.col.clear();
        chunk.val.clear();
        chunk.side.clear();
        // 8 bytes an entry (u32 column, float value).
        while (i < last && (chunk.nnz.empty() || chunk.col.size() * 8 < kRowChunkBytes)) read_row(i++, chunk);
        FFCUBE_CHECK(chunk.col.size() == chunk.val.size() && chunk.side.size() == chunk.nnz.size());
        pack_sides(chunk.side, sides);
        const std::uint64_t header[2] = {chunk.nnz.size(), chunk.col.size()};
        check(MPI_Send(header, 2, MPI_UINT64_T, 0, kTagChunk, MPI_COMM_WORLD), "MPI_Send");
        send_all<std::uint32_t>(chunk.nnz, 0, kTagChunkNnz);
        send_all<std::uint32_t>(chunk.col, 0, kTagChunkCol);
        send_all<float>(chunk.val, 0, kTagChunkVal);
        send_all<double>(sides, 0, kTagChunkSide);
    }
}

ReceivedRows receive_rows(int from, std::uint32_t first, std::uint32_t last,
                          const std::function<void(std::uint32_t, RowView)>& sink) {
    ReceivedRows figures;
    RowBlock chunk;
    std::vector<double> sides;
    std::uint32_t i = first;
    if (i < last) check(MPI_Send(&i, 1, MPI_UINT32_T, from, kTagAsk, MPI_COMM_WORLD), "MPI_Send");
    while (i < last) {
        std::uint64_t header[2] = {0, 0};
        check(MPI_Recv(header, 2, MPI_UINT64_T, from, kTagChunk, MPI_COMM_WORLD, MPI_STATUS_IGNORE), "MPI_Recv");
        FFCUBE_CHECK(header[0] > 0 && header[0] <= last - i);
        chunk.nnz.resize(header[0]);
        chunk.col.resize(header[1]);
        chunk.val.resize(header[1]);
        sides.resize(kSideWords * header[0]);
        recv_all<std::uint32_t>(chunk.nnz, from, kTagChunkNnz);
        recv_all<std::uint32_t>(chunk.col, from, kTagChunkCol);
        recv_all<float>(chunk.val, from, kTagChunkVal);
        recv_all<double>(sides, from, kTagChunkSide);
        ++figures.chunks;
        figures.largest_chunk_bytes =
            std::max<std::uint64_t>(figures.largest_chunk_bytes, (4 + 8 * kSideWords) * header[0] + 8 * header[1]);
        const std::uint32_t end = i + static_cast<std::uint32_t>(header[0]);
        // Ask for the next chunk before using this one: the rank reads and sends it meanwhile.
        if (end < last) check(MPI_Send(&end, 1, MPI_UINT32_T, from, kTagAsk, MPI_COMM_WORLD), "MPI_Send");
        std::size_t at = 0;
        for (std::uint32_t k = 0; k < header[0]; ++k) {
            FFCUBE_CHECK(at + chunk.nnz[k] <= chunk.col.size());
            sink(i + k, RowView{std::span<const std::uint32_t>(chunk.col).subspan(at, chunk.nnz[k]),
                                std::span<const float>(chunk.val).subspan(at, chunk.nnz[k]),
                                unpack_side(sides.data() + kSideWords * k)});
            at += chunk.nnz[k];
        }
        FFCUBE_CHECK(at == chunk.col.size());
        i = end;
    }
    return figures;
}

namespace {
void reduce_to_root(std::span<double> v, MPI_Op op) {
    for (std::size_t at = 0; at < v.size(); at += kChunk) {
        const int n = static_cast<int>(std::min(kChunk, v.size() - at));
        check(g_rank == 0 ? MPI_Reduce(MPI_IN_PLACE, v.data() + at, n, MPI_DOUBLE, op, 0, MPI_COMM_WORLD)
                          : MPI_Reduce(v.data() + at, nullptr, n, MPI_DOUBLE, op, 0, MPI_COMM_WORLD),
              "MPI_Reduce");
    }
}
}  // namespace

void reduce_sum_to_root(std::span<double> v) { reduce_to_root(v, MPI_SUM); }
void reduce_min_to_root(std::span<double> v) { reduce_to_root(v, MPI_MIN); }

std::vector<std::uint64_t> gather_to_root(std::span<const std::uint64_t> mine) {
    FFCUBE_CHECK(mine.size() <= std::size_t(INT_MAX));
    std::vector<std::uint64_t> all(g_rank == 0 ? mine.size() * std::size_t(g_size) : 0);
    check(MPI_Gather(mine.data(), static_cast<int>(mine.size()), MPI_UINT64_T, all.data(), static_cast<int>(mine.size()),
                     MPI_UINT64_T, 0, MPI_COMM_WORLD),
          "MPI_Gather");
    return all;
}

WorldRowBlocks::WorldRowBlocks(std::vector<std::uint32_t> bounds) : bounds_(std::move(bounds)) {
    FFCUBE_CHECK(bounds_.size() == std::size_t(g_size) + 1);
    for (int r = 0; r < g_size; ++r) {
        FFCUBE_CHECK(bounds_[r + 1] - bounds_[r] <= INT_MAX);
        counts_.push_back(static_cast<int>(bounds_[r + 1] - bounds_[r]));
        displs_.push_back(static_cast<int>(bounds_[r]));
    }
}

std::uint32_t WorldRowBlocks::first() const { return bounds_[g_rank]; }
std::uint32_t WorldRowBlocks::last() const { return bounds_[g_rank + 1]; }

void WorldRowBlocks::share(std::span<double> x) {
    FFCUBE_CHECK(x.size() == bounds_.back());
    check(MPI_Allgatherv(MPI_IN_PLACE, 0, MPI_DATATYPE_NULL, x.data(), counts_.data(), displs_.data(), MPI_DOUBLE,
                         MPI_COMM_WORLD),
          "MPI_Allgatherv");
}

void WorldRowBlocks::sum(std::span<double> v) {
    gathered_.resize(v.size() * static_cast<std::size_t>(g_size));
    check(MPI_Allgather(v.data(), static_cast<int>(v.size()), MPI_DOUBLE, gathered_.data(), static_cast<int>(v.size()),
                        MPI_DOUBLE, MPI_COMM_WORLD),
          "MPI_Allgather");
    for (std::size_t k = 0; k < v.size(); ++k) {
        double s = 0.0;
        for (int r = 0; r < g_size; ++r) s += gathered_[std::size_t(r) * v.size() + k];
        v[k] = s;
    }
}

void WorldRowBlocks::max(std::span<double> v) {
    check(MPI_Allreduce(MPI_IN_PLACE, v.data(), static_cast<int>(v.size()), MPI_DOUBLE, MPI_MAX, MPI_COMM_WORLD),
          "MPI_Allreduce");
}

}  // namespace ffcube::mpi
