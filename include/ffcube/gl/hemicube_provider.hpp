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
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

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
    // Rows planned at 4 × 4 sub-hemicubes (RowPlan::sampled_fine: an occluder touches the
    // sender) ray-cast instead (docs/accuracy.md, "Rows an occluder touches, by rays"): the
    // worker's thread casts fine_row_rays rays from the whole sender through Embree
    // (RaycastRowProvider::cast_row, seeded by `seed`), which samples the sender as the
    // sub-hemicubes do, but at a cost that follows the rays and not the scene's pieces × 16
    // hemicubes. 0: max(N², min(4 N², 65,536)): 16,384 at N = 64, 65,536 at N = 128 and 256
    // (where it measured as accurate as the 16 sub-hemicubes or more: docs/benchmarks.md), N²
    // beyond. automatic: where rays_preferred (below: a mesh of kFineRowsByRaysMinPieces
    // facets or more, or of kRaysMinMeshPieces with one patch a facet or nearly), where the rays
    // cost no more than the 16 sub-hemicubes on llvmpipe and are the more accurate. Never on a
    // scene with obstruction-only surfaces (the ray caster credits either side of them; hemicubes the
    // facing one): automatic keeps hemicubes there, rays is an InputError.
    enum class FineRows { hemicubes, rays, automatic };
    FineRows fine_rows = FineRows::hemicubes;
    std::uint64_t fine_row_rays = 0;
    static constexpr std::size_t kFineRowsByRaysMinPieces = 1000;
    // Rays also for a mesh of kRaysMinMeshPieces pieces or more with at most
    // kRaysMaxPatchesPerPiece patches a piece on average (one patch a facet, as --no-subdivide
    // makes): on cities of 100, 300 and 600 facets the rays were faster and about twice as
    // accurate, and the drawn 4 × 4 rows biased towards sky (a wall standing on the sender is a
    // near-singular integrand that sixteen points miss); a scene of few pieces and many patches
    // (the Cornell box, 170 a piece) keeps hemicubes, whose rows there are the more accurate
    // (docs/benchmarks.md, "Rays in coherent packets, and --method auto").
    static constexpr std::size_t kRaysMinMeshPieces = 100;
    static constexpr std::size_t kRaysMaxPatchesPerPiece = 4;
    // Whether rows of a scene of these pieces and patches are better cast than drawn (on
    // llvmpipe; obstruction-only surfaces are the caller's to rule out).
    static bool rays_preferred(std::size_t pieces, std::size_t patches) {
        return pieces >= kFineRowsByRaysMinPieces ||
               (pieces >= kRaysMinMeshPieces && patches <= kRaysMaxPatchesPerPiece * pieces);
    }
    // fine_row_rays' default at resolution N: max(N²/2, min(2 N², 32,768)): 32,768 at N = 128
    // and 256. Half the count of the padded stratified sampler it replaced: the scrambled Sobol'
    // rays (raycast/sampling.hpp) are as accurate at half the rays (the 22,881-facet city: row L2
    // error 1.43e-3 at 32,768 against 1.46e-3 at 65,536 before; docs/benchmarks.md).
    static std::uint64_t default_fine_row_rays(int resolution) {
        const auto n = static_cast<std::uint64_t>(resolution > 0 ? resolution : 0);
        return std::max(n * n / 2, std::min<std::uint64_t>(2 * n * n, 32768));
    }
};

// What the provider did, summed over all hemicubes so far. Times are summed over workers
// (CPU-seconds, not wall time).
struct HemicubeStats {
    std::uint64_t hemicubes = 0;
    double prepare_seconds = 0;     // eye-relative transform and culling on the CPU
    double draw_seconds = 0;        // uploads and draw calls, up to glFinish
    double readback_seconds = 0;    // glReadPixels of the atlas
    double accumulate_seconds = 0;  // ΔF per ID into the row
    // Culling counts mesher pieces (Scene::grids: a face's quad or triangle, drawn whole; the
    // fragment shader finds the patch), summed over hemicubes.
    std::uint64_t pieces_considered = 0;              // pieces × hemicubes
    std::uint64_t pieces_behind = 0;                  // wholly behind the hemicube plane
    std::uint64_t pieces_tested = 0;                  // classified one by one (the others: PieceBvh)
    std::array<std::uint64_t, 5> pieces_drawn{};      // per face (top, +x, -x, +y, -y)
    std::array<std::uint64_t, 5> pieces_culled{};     // in front of the plane but outside the face
    std::array<std::uint64_t, 5> pieces_occluded{};   // in the face but behind the occluders
    std::uint64_t occlusion_hemicubes = 0;            // hemicubes that drew occluders first
    std::uint64_t nodes_occluded = 0;                 // hierarchy nodes × faces found hidden whole
    std::uint64_t pieces_occluded_by_node = 0;        // of pieces_occluded (all faces): left out by those
    // Hemicubes whose eye lay inside the scene's enclosure (enclosure_without_depth), and the
    // pieces × faces of it they drew without the depth test.
    std::uint64_t enclosure_hemicubes = 0;
    std::uint64_t enclosure_pieces_drawn = 0;
    // Of those, hemicubes drawn with no depth test at all (Enclosure::inner_flat: the other
    // pieces lie in one plane, a blocker or a partition).
    std::uint64_t depth_free_hemicubes = 0;
    double back_face_weight = 0;   // Σ ΔF of pixels that showed a back face
    double miss_weight = 0;        // Σ ΔF of pixels that showed nothing
    std::uint64_t self_hits = 0;   // pixels that showed the patch itself (should stay 0)
    std::uint64_t sampled_rows = 0;  // rows made of sub-hemicubes (compute_rows_planned)
    std::uint64_t skipped_rows = 0;  // rows the caller needed no hemicube for (RowPlan::skip)
    // Rows made of sub-hemicubes whose sender a facet cuts and partly encloses: measured at
    // points on its exposed part only (gl/exposed_points.hpp).
    std::uint64_t partly_enclosed_rows = 0;
    // Bytes sent to the GL per hemicube, summed: vertex data (the eye and frame) and the index lists.
    std::uint64_t upload_vertex_bytes = 0;
    std::uint64_t upload_index_bytes = 0;
    // Rows planned at 4 × 4 that were ray-cast instead (HemicubeOptions::fine_rows), and the
    // CPU-seconds their rays took (on the workers' threads in this process).
    std::uint64_t fine_rows_cast = 0;
    double cast_seconds = 0;
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
    // Sub-hemicubes: a flagged row is the average of hemicubes at the patch's 2 × 2 quadrature
    // points (3 on a triangle), weights by area, each with its own visibility, rendered at half
    // the resolution (when that is even and ≥ 8): about the cost and pixel noise of one hemicube.
    bool can_sample_sender() const override { return true; }
    std::uint64_t cast_fine_row_rays() const override { return fine_rows_by_rays() ? fine_row_rays() : 0; }
    void compute_rows_planned(std::span<const std::uint32_t> rows, std::span<const RowPlan> plans,
                              const RowSink& sink) override;
    // The stages run on the worker's thread in the calling process, around its row: plan, the
    // hemicube (in the worker process, or on the thread's own context), finish; so one worker's
    // finish overlaps the others' drawing, and the calling thread only hands rows on.
    void compute_rows_staged(std::span<const std::uint32_t> rows, const RowStages& stages,
                             const RowSink& sink) override;

    // The item buffer of patch i's hemicube: the atlas (3N × N, row 0 at the bottom; see
    // hemicube/layout.hpp), each pixel 0 (nothing), 1 + patch index, or 0xFFFFFFFF (a back face).
    std::vector<std::uint32_t> item_buffer(std::uint32_t i);

    // Makes the workers draw another scene (the next adaptive level's elements) without
    // restarting them: forked workers are sent the scene (io/scene_blob.hpp) and rebuild their
    // pieces and GL state; thread workers rebuild theirs on their own thread before their next
    // row. Rows are then the same bits as a new provider's on `scene` (tested). The counters
    // (stats()) start again from zero. Not while a compute_rows call runs; `scene` must outlive
    // this (or the next set_scene). Throws InputError as the constructor does, IoError when a
    // worker process cannot take the scene.
    void set_scene(const Scene& scene);

    HemicubeStats stats() const;
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
    // Whether rows planned at 4 × 4 are ray-cast on this scene (HemicubeOptions::fine_rows,
    // automatic resolved), and with how many rays each.
    bool fine_rows_by_rays() const;
    std::uint64_t fine_row_rays() const;

    // Where the eye sits above the patch and where the near plane lies, as fractions of the
    // patch's longest edge (relative, never absolute units).
    static constexpr double kEyeOffset = 1e-5;
    static constexpr double kNear = 1e-6;

private:
    struct Impl;
    std::unique_ptr<Impl> impl_;
};

}  // namespace ffcube
