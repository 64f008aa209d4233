// Rows of F by hemicubes: for each patch, five faces rendered as a 32-bit item buffer on a
// headless GL context, and the exact delta form factor of each pixel added to the row entry of
// the patch it shows. One GL context and one thread per worker.
//
// What is drawn is the mesher's pieces (Scene::grids), not the patches: a wall split into
// 20×20 patches is two triangles, and the fragment shader finds the patch from the fragment's
// position in the piece. The cost of a hemicube then hardly depends on how finely the scene is
// meshed (llvmpipe's cost is per triangle set up, then per pixel).
#pragma once

#include <array>
#include <cmath>
#include <cstdint>
#include <memory>
#include <string>
#include <string_view>
#include <vector>

#include "ffcube/core/stats.hpp"
#include "ffcube/formfactor/row_provider.hpp"
#include "ffcube/gl/context.hpp"
#include "ffcube/scene/scene.hpp"

namespace ffcube {

struct HemicubeOptions {
    int resolution = 256;     // top-face pixels per side; even, 8..8192
    unsigned threads = 0;     // worker threads and GL contexts; 0 = every core
    Backend backend = Backend::Auto;
    bool rotate = true;       // rotate each hemicube about the normal by a seeded angle
    std::uint64_t seed = 0x5eed;
    // Workers may be forked processes (when this process has no thread and no context yet).
    // false: always threads, each with its own context; an MPI rank must not fork (src/mpi).
    bool worker_processes = true;
    // Occlusion culling (docs/architecture.md, "Culling"): in a hemicube of many pieces, those
    // wholly behind the pieces the worker's previous hemicube showed (drawn first, depth only)
    // are not drawn. The item buffers are the same bits either way (tested); false: draw all.
    bool occlusion_culling = true;
    // With it, whole nodes of the pieces' hierarchy hidden on a face are left out at once
    // (hemicube/occlusion.hpp, hide_hidden_nodes): the same pieces as testing each, fewer tests.
    // false: every piece tested on its own (tests compare the two).
    bool occlusion_nodes = true;
    // The scene's enclosure (hemicube/pieces.hpp, Enclosure: a convex room's walls, a city's flat
    // ground) drawn without the depth test from every eye inside it, the other pieces over it
    // with the depth test (docs/architecture.md, "Culling"). The item buffers are the same bits
    // either way (tested); false: every piece depth-tested.
    bool enclosure_without_depth = true;
};

// The hemicube's faces in the order of its per-face statistics (hemicube/layout.hpp).
inline constexpr std::array<std::string_view, 5> kHemicubeFaceNames{"top", "pos_x", "neg_x", "pos_y", "neg_y"};
using PerFace = stats::PerPart<std::uint64_t, 5, kHemicubeFaceNames>;

// What the provider did, summed over all hemicubes so far, declared once each with its report
// key and merge rule (core/stats.hpp): merged over workers, sent back by worker processes and
// reported from this list. Times are summed over workers (CPU-seconds, not wall time).
#define FFCUBE_HEMICUBE_STATS(X)                                                                                   \
    X(std::uint64_t, hemicubes, sum, "hemicubes")                                                                 \
    X(double, prepare_seconds, sum, "time.prepare")       /* eye-relative transform and culling on the CPU */     \
    X(double, draw_seconds, sum, "time.drawing")          /* uploads and draw calls, up to glFinish */            \
    X(double, readback_seconds, sum, "time.readback")     /* glReadPixels of the atlas */                         \
    X(double, accumulate_seconds, sum, "time.accumulation") /* dF per ID into the row */                          \
    /* Culling counts mesher pieces (Scene::grids: a face's quad or triangle, drawn whole; the                     \
       fragment shader finds the patch), summed over hemicubes: pieces x hemicubes, those wholly                   \
       behind the hemicube plane, those classified one by one (the others: PieceBvh). */                           \
    X(std::uint64_t, pieces_considered, sum, "left_out.pieces_considered")                                        \
    X(std::uint64_t, pieces_behind, sum, "left_out.pieces_behind_plane")                                          \
    X(std::uint64_t, pieces_tested, sum, "left_out.pieces_tested")                                                \
    /* Per face: drawn; in front of the plane but outside the face; in the face but behind the                     \
       occluders. */                                                                                               \
    X(PerFace, pieces_drawn, sum, "drawn.pieces_per_face")                                                        \
    X(PerFace, pieces_culled, sum, "left_out.pieces_culled_per_face")                                             \
    X(PerFace, pieces_occluded, sum, "left_out.pieces_occluded_per_face")                                         \
    /* Hemicubes that drew occluders first; hierarchy nodes x faces found hidden whole; of                         \
       pieces_occluded (all faces), those left out by such nodes. */                                               \
    X(std::uint64_t, occlusion_hemicubes, sum, "left_out.occlusion_hemicubes")                                    \
    X(std::uint64_t, nodes_occluded, sum, "left_out.nodes_occluded")                                              \
    X(std::uint64_t, pieces_occluded_by_node, sum, "left_out.pieces_occluded_by_node")                            \
    /* Hemicubes whose eye lay inside the scene's enclosure (enclosure_without_depth), and the                     \
       pieces x faces of it they drew without the depth test; of those hemicubes, the ones drawn                   \
       with no depth test at all (Enclosure::inner_flat: the other pieces lie in one plane). */                    \
    X(std::uint64_t, enclosure_hemicubes, sum, "drawn.enclosure_hemicubes")                                       \
    X(std::uint64_t, enclosure_pieces_drawn, sum, "drawn.enclosure_pieces_drawn")                                 \
    X(std::uint64_t, depth_free_hemicubes, sum, "drawn.depth_free_hemicubes")                                     \
    /* sum of dF of pixels that showed a back face, and nothing, in units of kWeightUnit (reported per            \
       hemicube: coverage.*; read through back_face_weight(), miss_weight()) */                                   \
    X(std::uint64_t, back_face_units, sum, "")                                                                    \
    X(std::uint64_t, miss_units, sum, "")                                                                         \
    X(std::uint64_t, self_hits, sum, "self_hits") /* pixels that showed the patch itself (should stay 0) */       \
    X(std::uint64_t, sampled_rows, sum, "sub_hemicube_rows") /* rows made of sub-hemicubes (sampled) */           \
    X(std::uint64_t, skipped_rows, sum, "rows_not_rendered") /* rows needing no hemicube (RowPlan::skip) */       \
    /* Rows made of sub-hemicubes whose sender a facet cuts and partly encloses: measured at points                \
       on its exposed part only (RowRequest::partly_enclosed; accuracy/exposed_points.hpp). */                     \
    X(std::uint64_t, partly_enclosed_rows, sum, "sub_hemicube_rows_partly_enclosed")                              \
    /* Bytes sent to the GL per hemicube, summed: vertex data (the eye and frame), index lists. */                 \
    X(std::uint64_t, upload_vertex_bytes, sum, "upload.vertex_bytes")                                             \
    X(std::uint64_t, upload_index_bytes, sum, "upload.index_bytes")                                               \
    /* Rows the driver had ray-cast instead (RowEngine::rays: rows planned at 4 x 4 on a scene                     \
       where rays are preferred, pipeline/row_engine.hpp), through RowStages::cast on the workers'                 \
       threads in this process, and the CPU-seconds their rays took. */                                            \
    X(std::uint64_t, fine_rows_cast, sum, "fine_rows.cast")                                                       \
    X(double, cast_seconds, sum, "time.fine_row_rays")

struct HemicubeStats {
    FFCUBE_STATS(HemicubeStats, FFCUBE_HEMICUBE_STATS)

    // The weights are summed as integers of 2^-32, so that their totals are the same bits in any
    // order of threads, worker processes and MPI ranks (a sum of doubles is not): the report's
    // coverage figures do not depend on the thread count or the load. Each hemicube's weight
    // (at most 1) is rounded to the nearest unit, but a positive weight counts at least one, so
    // "some pixel saw nothing" (the closure evidence, accuracy/enforce.hpp) is kept exactly.
    // 2^64 units hold 2^32 hemicubes' worth of weight 1.
    static constexpr double kWeightUnit = 0x1p-32;
    static std::uint64_t weight_units(double w) {
        if (!(w > 0)) return 0;
        const auto u = static_cast<std::uint64_t>(std::llround(w / kWeightUnit));
        return u > 0 ? u : 1;
    }
    double back_face_weight() const { return static_cast<double>(back_face_units) * kWeightUnit; }
    double miss_weight() const { return static_cast<double>(miss_units) * kWeightUnit; }
};

class HemicubeRowProvider final : public RowProvider {
public:
    // Starts the workers and their GL contexts; throws GlError (listing every backend tried) when
    // no context can be created, InputError for a bad resolution. The scene must outlive this.
    HemicubeRowProvider(const Scene& scene, const HemicubeOptions& options);
    ~HemicubeRowProvider() override;

    std::uint32_t size() const override;
    std::string name() const override { return "hemicube"; }
    void compute_rows(std::span<const std::uint32_t> rows, const RowSink& sink) override;
    // Sub-hemicubes: a sampled row is the weighted sum of hemicubes at the request's sender
    // points (without points: the patch's 2 × 2 or 4 × 4 quadrature points, weights by area),
    // each with its own visibility, rendered at half the resolution (when that is even and ≥ 8):
    // with 2 × 2, about the cost and pixel noise of one hemicube. Requests name this engine
    // (RowEngine::provider) only.
    bool can_sample_sender() const override { return true; }
    void compute_rows_requested(std::span<const std::uint32_t> rows, std::span<const RowRequest> requests,
                                const RowSink& sink) override;
    // The stages run on the worker's thread in the calling process, around its row: plan, the
    // hemicube (in the worker process, or on the thread's own context) or the stages' cast (a
    // row the plan gave to the ray caster, cast while the worker process draws the row before),
    // finish; so one worker's finish overlaps the others' drawing, and the calling thread only
    // hands rows on.
    void compute_rows_staged(std::span<const std::uint32_t> rows, const RowStages& stages,
                             const RowSink& sink) override;

    // The item buffer of patch i's hemicube: the atlas (3N × N, row 0 at the bottom; see
    // hemicube/layout.hpp), each pixel 0 (nothing), 1 + patch index, or 0xFFFFFFFF (a back face).
    std::vector<std::uint32_t> item_buffer(std::uint32_t i);

    // Makes the workers draw another scene (the next adaptive level's elements) without
    // restarting them: forked workers are sent the scene (scene/scene_blob.hpp) and rebuild their
    // pieces and GL state; thread workers rebuild theirs on their own thread before their next
    // row. Rows are then the same bits as a new provider's on `scene` (tested). The counters
    // (stats()) start again from zero. Not while a compute_rows call runs; `scene` must outlive
    // this (or the next set_scene). Throws InputError as the constructor does, IoError when a
    // worker process cannot take the scene.
    void set_scene(const Scene& scene);

    HemicubeStats stats() const;
    // Adds another process's statistics to these (an MPI rank's, merged onto rank 0's).
    void merge_stats(const HemicubeStats& other);
    std::string backend() const;   // e.g. "egl-surfaceless"
    std::string renderer() const;  // GL_RENDERER
    unsigned threads() const;
    // "processes" (one forked child per worker, each with its own GL context: llvmpipe scales
    // across processes, not across contexts of one process) or "threads" (used for one worker,
    // or when forking is unsafe: this process already made a GL context or runs other threads).
    std::string workers() const;
    int resolution() const;
    // The scene's enclosure drawn without the depth test (HemicubeOptions::enclosure_without_depth;
    // hemicube/pieces.hpp): its planes and pieces, 0 when off or when the scene has none.
    std::size_t enclosure_planes() const;
    std::size_t enclosure_pieces() const;

    // Where the eye sits above the patch and where the near plane lies, as fractions of the
    // patch's longest edge (relative, never absolute units).
    static constexpr double kEyeOffset = 1e-5;
    static constexpr double kNear = 1e-6;

private:
    struct Impl;
    std::unique_ptr<Impl> impl_;
};

}  // namespace ffcube
