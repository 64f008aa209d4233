// The GL worker: one GL context current on one thread (or in one worker process), its item
// buffers and its scratch space; renders a patch's hemicube and turns it into a row.
#pragma once

#include <array>
#include <cstdint>
#include <memory>
#include <span>
#include <vector>

#include "ffcube/formfactor/sparse.hpp"
#include "ffcube/gl/context.hpp"
#include "ffcube/gl/hemicube_provider.hpp"
#include "ffcube/hemicube/layout.hpp"
#include "ffcube/hemicube/occlusion.hpp"
#include "ffcube/hemicube/pieces.hpp"
#include "ffcube/scene/scene.hpp"
#include "gl/engine.hpp"
#include "gl/objects.hpp"

namespace ffcube {

// Pixel value of a back face in the item buffer (0 is nothing, 1 + patch a front face).
inline constexpr std::uint32_t kBackFace = 0xFFFFFFFFu;
// Hemicubes that list fewer pieces than this draw them all at once: occlusion culling's extra
// pass and depth readback would cost more than the pieces it can leave out.
inline constexpr std::size_t kOcclusionMinPieces = 128;
// Occluders chosen by angular size (Worker::occlude), besides those the last hemicube showed.
inline constexpr std::size_t kOccluderCount = 32;

// Resolution of sub-hemicubes: half the row's, when that is still a valid resolution (even, ≥ 8).
int half_resolution(int n);

class Worker {
public:
    // ctx must be current on this thread, now and for every call. Everything referenced must
    // outlive the worker.
    Worker(GlContext& ctx, const Scene& scene, const ScenePieces& pieces, const HemicubeLayout& layout,
           const HemicubeOptions& opt);

    // Renders patch p's hemicube into ids() (the atlas).
    void render(std::uint32_t p, HemicubeStats& st) { render(p, scene_.patches[p].centroid, Res::full, st); }
    // Renders the hemicube of patch p from the point 'at' on it (its centroid, or a quadrature
    // point for sub-hemicubes), raised by kEyeOffset of the patch size, into the full atlas or
    // (half) the half-resolution one of sub-hemicubes.
    // Which atlas a hemicube is drawn into: the row's resolution or half_resolution.
    enum class Res { full, half };
    void render(std::uint32_t p, const Vec3& at, Res res, HemicubeStats& st);
    // Row p: one hemicube at the centroid (no points), or the weighted sum of sub-hemicubes at
    // the given sender points (at half_resolution), each with its own visibility.
    void row(std::uint32_t p, std::span<const Vec3> points, std::span<const double> weights, SparseRow& out,
             HemicubeStats& st);
    const std::vector<std::uint32_t>& ids() const { return ids_; }

private:
    // A piece cull() found may show: the faces it goes to (bit f) and the pass (front or back).
    struct Drawn {
        std::uint32_t g;
        std::uint8_t faces;
        bool back;
        bool occluder = false;  // drawn first by occlude()
    };
    void accumulate(std::uint32_t p, double weight, Res res, HemicubeStats& st);
    void take_row(SparseRow& out, HemicubeStats& st);
    template <class F>
    void for_each_id_run(const std::vector<std::uint32_t>& ids, const HemicubeLayout& lay, F&& f);
    // A new row in acc_/touched_: a new epoch_, nothing touched.
    void begin_row();
    void accumulate_points(std::uint32_t p, std::span<const Vec3> points, std::span<const double> weights, Res res,
                           HemicubeStats& st);
    std::uint32_t column_of(std::uint32_t p, std::size_t k, std::uint32_t id) const;  // id − 1, checked
    [[noreturn]] void bad_id(std::uint32_t p, std::size_t k, std::uint32_t id) const;  // column_of's failure
    void touch(std::uint32_t j);        // column j enters the row being made (epoch_) at 0
    void first_touch(std::uint32_t j);  // touch's work when j is not in the row yet
    void end_seen();  // the pieces the last hemicube showed become the next one's occluders
    // One hemicube of patch p at `at` (half resolution or full), weight 1, as its own row in out.
    void hemicube_row(std::uint32_t p, const Vec3& at, Res res, SparseRow& out, HemicubeStats& st);
    void cull(HemicubeStats& st);
    void occlude(const std::array<FaceSpec, 5>& faces, double near, Res res, const Vec3& eye, const HemicubeFrame& fr,
                 HemicubeStats& st);
    const HemicubeLayout& layout_of(Res res) const {
        return res == Res::full ? layout_ : half_layout_;
    }
    void build_lists(bool occluders_only, HemicubeStats* st);
    void add_to_lists(const Drawn& d, std::size_t list0, HemicubeStats* st);
    void upload_lists(HemicubeStats& st);
    void draw_lists(const std::array<FaceSpec, 5>& faces, double near, int passes, bool depth_free);

    const gl::Api& gl_;
    const Scene& scene_;
    const ScenePieces& pieces_;
    const HemicubeLayout& layout_;
    const HemicubeLayout half_layout_;  // sub-hemicubes (half_resolution)
    const HemicubeOptions& opt_;
    // Test hook (docs/robustness.md): FFCUBE_TEST_WORKER_FAIL=input|io|internal|gl makes every
    // row throw that class of error, from inside the worker (thread or process). 0: unset.
    int test_fail_ = 0;
    std::array<FaceSpec, 5> face_m_, half_face_m_;
    // Front pass: one program per group of pieces (groups_ of them: one for a scene of one patch
    // per piece, else one per kind of piece present), group_of_kind_[kind] (3, 4 or 5) its group.
    std::array<gl::Program, 3> programs_;
    std::uint32_t groups_ = 0;
    std::array<std::uint32_t, 6> group_of_kind_{};
    gl::Program back_program_;
    gl::ItemTarget target_, half_target_;
    gl::VertexArray vao_;
    gl::Buffer vbo_, static_vbo_, grid_vbo_, info_vbo_, ebo_;  // grid_vbo_: general quads' corners
    gl::Buffer eye_ubo_;  // the eye and frame (item.vert's HemicubeEye)
    std::array<GLint, 3> u_face_{-1, -1, -1};
    GLint u_back_face_ = -1;
    std::vector<float> local_;
    std::vector<std::uint32_t> visit_;  // per piece: == visit_stamp_ when it may be in front (PieceBvh)
    std::uint32_t visit_stamp_ = 0;
    std::vector<Drawn> drawn_;                          // cull()'s pieces, in piece order
    // Index lists per face: front pieces of group k at [5k, 5k + 5), back pieces at [kBackLists, kBackLists + 5).
    // The enclosure's front pieces of group k (drawn without the depth test, first) at
    // [kEnclosureLists + 5k, + 5), in reverse piece order.
    static constexpr std::size_t kBackLists = 15, kEnclosureLists = 20, kLists = 35;
    bool enclosure_now_ = false;  // this hemicube's eye lies inside the enclosure (pieces_.enclosure)
    bool depth_free_ = false;     // ... and the other pieces need no depth test (Enclosure::inner_flat)
    std::vector<std::uint32_t> lists_[kLists], all_idx_;
    // Occlusion culling (occlude()): the pieces that showed in this worker's last hemicube are
    // drawn first, as occluders, and what lies wholly behind them is left out.
    std::vector<std::uint32_t> piece_of_;  // per patch: its piece
    std::vector<std::uint32_t> seen_;      // per piece: == seen_stamp_ when the last hemicube showed it
    bool occluders_ = true;                // occlude() may run: accumulate() keeps seen_ (else unused)
    bool dense_ = false;                   // rows taken by a pass over acc_, not by touched_ (take_row)
    std::uint32_t seen_stamp_ = 1, last_stamp_ = 0;
    std::vector<float> depth_;
    std::array<FaceDepthRows, 5> depth_rows_;
    HiddenFaces hidden_;  // occlude(): per piece, the faces a hidden hierarchy node leaves it out of
    std::vector<Vec3> corners_;
    std::vector<std::pair<double, std::uint32_t>> scores_;  // (angular size, drawn_ index)
    struct Sphere {
        Vec3 centre{0.0};
        double radius = 0;
    };
    std::vector<Sphere> sphere_;  // per piece: its corners' mean and their largest distance from it
    std::vector<std::uint32_t> ids_, half_ids_;
    std::vector<double> acc_;
    std::vector<std::uint64_t> run_bits_;  // accumulate(): where runs of one id start in a line
    std::vector<std::uint32_t> stamp_, touched_;
    std::uint32_t epoch_ = 0;
};

// A worker in this process: the context is made current on the worker thread (start).
class LocalEngine final : public Engine {
public:
    LocalEngine(std::unique_ptr<GlContext> ctx, const Scene& scene, const ScenePieces& pieces,
                const HemicubeLayout& layout, const HemicubeOptions& opt)
        : ctx_(std::move(ctx)), scene_(&scene), pieces_(&pieces), layout_(layout), opt_(opt) {}
    ~LocalEngine() override { ctx_.reset(); }
    void start() override;
    void row(std::uint32_t p, std::span<const Vec3> points, std::span<const double> weights, SparseRow& out,
             HemicubeStats& st) override;
    void item_buffer(std::uint32_t p, std::vector<std::uint32_t>& out) override;
    void stop() override;
    // The Worker is rebuilt on this engine's thread (where its context is current) at the next request.
    void set_scene(const Scene& scene, const ScenePieces& pieces) override;

private:
    Worker& worker();  // the Worker for the current scene, rebuilt after set_scene

    std::unique_ptr<GlContext> ctx_;
    const Scene* scene_;
    const ScenePieces* pieces_;
    bool stale_ = false;
    const HemicubeLayout& layout_;
    const HemicubeOptions& opt_;
    std::unique_ptr<Worker> worker_;
};

}  // namespace ffcube
