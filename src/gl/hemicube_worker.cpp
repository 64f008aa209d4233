#include "gl/hemicube_worker.hpp"

#include <fmt/format.h>
#include <glm/geometric.hpp>

#include <algorithm>
#include <bit>
#include <csignal>
#include <cstdlib>
#include <cstring>
#include <numbers>
#include <string>

#include "ffcube/core/error.hpp"
#include "ffcube/core/timer.hpp"
#include "ffcube/hemicube/frame.hpp"
#include "ffcube/hemicube/outcode.hpp"
#include "ffcube/hemicube/runs.hpp"
#include "gl/gl_api.hpp"
#include "gl/shaders.hpp"

namespace ffcube {

int half_resolution(int n) { return n / 2 >= 8 && (n / 2) % 2 == 0 ? n / 2 : n; }

Worker::Worker(GlContext& ctx, const Scene& scene, const ScenePieces& pieces, const HemicubeLayout& layout,
       const HemicubeOptions& opt)
    : gl_(ctx.api()), scene_(scene), pieces_(pieces), layout_(layout), half_layout_(half_resolution(layout.resolution())),
      opt_(opt) {
    const gl::Api& gl = gl_;
    // The fragment shader specialised to the piece kinds of the scene: llvmpipe runs both
    // sides of a branch under a mask, so a path no piece takes still costs every pixel.
    std::string frag(shaders::item_frag);
    const std::size_t eol = frag.find('\n') + 1;
    const std::string kinds = fmt::format("#define HAS_TRIANGLES {}\n#define HAS_BILINEAR {}\n", pieces.has_kind[3] ? 1 : 0,
                                          pieces.has_kind[4] ? 1 : 0);
    // The scene's world positions go to the GL once, as doubles, and the vertex shader makes each
    // hemicube's eye-relative positions (docs/architecture.md, "Vertex data").
    const std::string positions = "#define WORLD_POSITIONS 1\n";
    std::string back_frag = frag;
    back_frag.insert(eol, kinds + "#define BACK_PASS 1\n");
    std::string back_vert(shaders::item_vert);
    back_vert.insert(back_vert.find('\n') + 1, kinds + positions);
    // The front pass: scenes of one patch per piece get one program that interpolates nothing
    // (SINGLE_CELL, item.vert); others one program per kind of piece they have (ONLY_KIND,
    // item.frag), each computing only its own kind's lookup, drawn one after the other.
    const auto front = [&](const std::string& defines, const std::string& name) {
        std::string f = frag, v(shaders::item_vert);
        f.insert(eol, defines);
        v.insert(v.find('\n') + 1, defines + positions);
        return gl::make_program(gl, name, v, f);
    };
    group_of_kind_.fill(0);
    if (pieces.single_cell) {
        programs_[0] = front(kinds + "#define SINGLE_CELL 1\n", "item shader");
        groups_ = 1;
    } else {
        for (const std::uint32_t kind : {3u, 5u, 4u}) {
            if (!pieces.has_kind[kind]) continue;
            group_of_kind_[kind] = groups_;
            programs_[groups_++] = front(fmt::format("#define HAS_TRIANGLES {}\n#define HAS_BILINEAR {}\n#define ONLY_KIND {}\n",
                                                     kind == 3 ? 1 : 0, kind == 4 ? 1 : 0, kind),
                                         fmt::format("item shader (pieces of kind {})", kind));
        }
        if (groups_ == 0) programs_[groups_++] = front(kinds, "item shader");  // no piece at all
    }
    // The back pass's own program: its discard (item.frag) would cost the front pass early depth tests.
    back_program_ = gl::make_program(gl, "item shader (back faces)", back_vert, back_frag);
    target_ = gl::make_item_target(gl, layout.atlas_width(), layout.atlas_height());
    half_target_ = gl::make_item_target(gl, half_layout_.atlas_width(), half_layout_.atlas_height());
    vao_ = gl::make_vertex_array(gl);
    vbo_ = gl::make_buffer(gl);
    static_vbo_ = gl::make_buffer(gl);
    grid_vbo_ = gl::make_buffer(gl);
    info_vbo_ = gl::make_buffer(gl);
    ebo_ = gl::make_buffer(gl);
    const std::size_t slots = pieces.pos.size();
    gl.BindVertexArray(vao_.id());
    gl.BindBuffer(GL_ARRAY_BUFFER, vbo_.id());
    gl.EnableVertexAttribArray(0);
    {
        // The vertex slots' world positions, once (item.vert, WORLD_POSITIONS).
        static_assert(sizeof(Vec3) == 3 * sizeof(double));
        gl.BufferData(GL_ARRAY_BUFFER, static_cast<GLsizeiptr>(std::max<std::size_t>(slots, 1) * sizeof(Vec3)),
                      slots ? pieces.pos.data() : nullptr, GL_STATIC_DRAW);
        gl.VertexAttribLPointer(0, 3, GL_DOUBLE, sizeof(Vec3), nullptr);
        eye_ubo_ = gl::make_buffer(gl);
        gl.BindBuffer(GL_UNIFORM_BUFFER, eye_ubo_.id());
        gl.BufferData(GL_UNIFORM_BUFFER, 16 * sizeof(double), nullptr, GL_STREAM_DRAW);
        gl.BindBufferBase(GL_UNIFORM_BUFFER, 1, eye_ubo_.id());
    }
    gl.BindBuffer(GL_ARRAY_BUFFER, static_vbo_.id());
    gl.BufferData(GL_ARRAY_BUFFER, static_cast<GLsizeiptr>(pieces.param.size() * sizeof(float)), pieces.param.data(),
                  GL_STATIC_DRAW);
    gl.EnableVertexAttribArray(1);
    gl.VertexAttribPointer(1, 2, GL_FLOAT, GL_FALSE, 2 * sizeof(float), nullptr);
    if (pieces.has_kind[4]) {
        // General quads' corners 1..3 in their plane (GpuGrid q1, q2, q3) per vertex slot, for the
        // inverse bilinear map (item.vert passes them flat: a read per pixel from a buffer, a
        // gather in llvmpipe, cost as much as the rest of the drawing).
        std::vector<float> q(pieces.grid.size() * 6);
        for (std::size_t v = 0; v < pieces.grid.size(); ++v) {
            const GpuGrid& g = pieces.gpu[pieces.grid[v]];
            std::copy(g.q1, g.q1 + 2, &q[v * 6]);
            std::copy(g.q2, g.q2 + 2, &q[v * 6 + 2]);
            std::copy(g.q3, g.q3 + 2, &q[v * 6 + 4]);
        }
        gl.BindBuffer(GL_ARRAY_BUFFER, grid_vbo_.id());
        gl.BufferData(GL_ARRAY_BUFFER, static_cast<GLsizeiptr>(q.size() * sizeof(float)), q.data(), GL_STATIC_DRAW);
        gl.EnableVertexAttribArray(2);
        gl.VertexAttribPointer(2, 2, GL_FLOAT, GL_FALSE, 6 * sizeof(float), nullptr);
        gl.EnableVertexAttribArray(4);
        gl.VertexAttribPointer(4, 2, GL_FLOAT, GL_FALSE, 6 * sizeof(float), reinterpret_cast<const void*>(2 * sizeof(float)));
        gl.EnableVertexAttribArray(5);
        gl.VertexAttribPointer(5, 2, GL_FLOAT, GL_FALSE, 6 * sizeof(float), reinterpret_cast<const void*>(4 * sizeof(float)));
    }
    gl.BindBuffer(GL_ARRAY_BUFFER, info_vbo_.id());
    gl.BufferData(GL_ARRAY_BUFFER, static_cast<GLsizeiptr>(pieces.info.size() * sizeof(std::uint32_t)),
                  pieces.info.data(), GL_STATIC_DRAW);
    gl.EnableVertexAttribArray(3);
    gl.VertexAttribIPointer(3, 4, GL_UNSIGNED_INT, 4 * sizeof(std::uint32_t), nullptr);
    gl.BindBuffer(GL_ELEMENT_ARRAY_BUFFER, ebo_.id());
    gl.UseProgram(back_program_.id());
    u_back_face_ = gl.GetUniformLocation(back_program_.id(), "u_face");
    for (std::uint32_t k = 0; k < groups_; ++k) u_face_[k] = gl.GetUniformLocation(programs_[k].id(), "u_face");
    gl.UseProgram(programs_[0].id());
    // All state the item pass needs is set here and never changed: nothing leaks in or out.
    gl.BindFramebuffer(GL_FRAMEBUFFER, target_.fbo.id());
    gl.Enable(GL_DEPTH_TEST);
    gl.DepthFunc(GL_GREATER);
    gl.DepthMask(GL_TRUE);
    gl.ClipControl(GL_LOWER_LEFT, GL_ZERO_TO_ONE);
    gl.Disable(GL_CULL_FACE);  // back faces must block (they write kBackFace)
    gl.Disable(GL_BLEND);
    gl.Disable(GL_DITHER);
    gl.Disable(GL_MULTISAMPLE);
    gl.Disable(GL_FRAMEBUFFER_SRGB);
    gl.Disable(GL_SCISSOR_TEST);
    gl.PixelStorei(GL_PACK_ALIGNMENT, 4);
    gl::check_gl(gl, "hemicube worker setup");

    local_.resize(slots * 3);
    visit_.assign(scene.grids.size(), 0u);
    for (std::size_t f = 0; f < 5; ++f) {
        face_m_[f] = layout.faces()[f];
        half_face_m_[f] = half_layout_.faces()[f];
    }
    half_ids_.resize(static_cast<std::size_t>(half_layout_.atlas_width()) * half_layout_.atlas_height());
    for (auto& l : lists_) l.reserve(slots);
    all_idx_.reserve(slots * 2);
    ids_.resize(static_cast<std::size_t>(layout.atlas_width()) * layout.atlas_height());
    acc_.assign(scene.patches.size(), 0.0);
    piece_of_.resize(scene.patches.size());
    for (std::size_t g = 0; g < scene.grids.size(); ++g) {  // grids are in patch order
        const std::size_t end = g + 1 < scene.grids.size() ? scene.grids[g + 1].first_patch : scene.patches.size();
        for (std::size_t c = scene.grids[g].first_patch; c < end; ++c) piece_of_[c] = static_cast<std::uint32_t>(g);
    }
    seen_.assign(scene.grids.size(), 0u);
    // occlude() runs only in hemicubes of kOcclusionMinPieces pieces or more: in a smaller scene
    // no hemicube needs the pieces the last one showed.
    occluders_ = opt.occlusion_culling && scene.grids.size() >= kOcclusionMinPieces;
    // Rows listed by a pass over acc_ (take_row) where the scene has at most 3N²/8 patches (an
    // eighth of a hemicube's pixels): that pass costs less than a stamp test per run of pixels.
    dense_ = scene.patches.size() <= 3 * static_cast<std::size_t>(layout.resolution()) * layout.resolution() / 8;
    // Per piece its corners' mean and their largest distance from it, in world coordinates
    // (occlude()'s angular sizes; a distance does not depend on the frame).
    sphere_.assign(scene.grids.size(), Sphere{});
    for (std::size_t g = 0; g < scene.grids.size(); ++g) {
        const PatchGrid& pg = scene.grids[g];
        Vec3 c(0.0);
        for (std::uint32_t v = 0; v < pg.count; ++v) c += pg.corners[v];
        c /= static_cast<double>(pg.count);
        double r2 = 0;
        for (std::uint32_t v = 0; v < pg.count; ++v) r2 = std::max(r2, glm::dot(pg.corners[v] - c, pg.corners[v] - c));
        sphere_[g] = {c, std::sqrt(r2)};
    }
    depth_.resize(static_cast<std::size_t>(layout.atlas_width()) * layout.atlas_height());
    stamp_.assign(scene.patches.size(), 0);
    if (const char* fail = std::getenv("FFCUBE_TEST_WORKER_FAIL"); fail && *fail) {
        const std::string f = fail;
        test_fail_ = f == "input" ? 1 : f == "io" ? 2 : f == "internal" ? 3 : f == "gl" ? 4 : f == "kill" ? 5 : -1;
    }
}

namespace {

// The test hook FFCUBE_TEST_WORKER_FAIL (docs/robustness.md): an error of the class asked for,
// raised inside the worker as the real ones are.
[[noreturn]] void fail_for_test(int what, std::uint32_t p) {
    const std::string where = fmt::format("row {} (test hook FFCUBE_TEST_WORKER_FAIL)", p);
    switch (what) {
        case 1: throw InputError(where + ": input error");
        case 2: throw IoError(where + ": I/O error");
        case 3: FFCUBE_CHECK_MSG(false, where); break;
        case 4: throw GlError(where + ": GL error");
        case 5: ::raise(SIGKILL); break;  // a worker killed from outside (the OOM killer, a user)
        default: break;
    }
    throw InputError("FFCUBE_TEST_WORKER_FAIL: use input, io, internal, gl or kill");
}

}  // namespace

// Renders the hemicube of patch p from the point 'at' on it (its centroid, or a quadrature
// point for sub-hemicubes), raised by kEyeOffset of the patch size, into the full atlas or
// (half) the half-resolution one of sub-hemicubes.
void Worker::render(std::uint32_t p, const Vec3& at, Res res, HemicubeStats& st) {
    const gl::Api& gl = gl_;
    const Patch& pa = scene_.patches[p];
    Stopwatch watch;
    const double angle = opt_.rotate ? hemicube_angle(opt_.seed, p) : 0.0;
    const HemicubeFrame fr = make_frame(pa.normal, angle);
    const Vec3 eye = at + pa.normal * (HemicubeRowProvider::kEyeOffset * pa.size);
    enclosure_now_ = opt_.enclosure_without_depth && !pieces_.enclosure.piece.empty() && pieces_.enclosure.contains(eye);
    depth_free_ = enclosure_now_ && pieces_.enclosure.inner_flat;
    st.enclosure_hemicubes += enclosure_now_;
    st.depth_free_hemicubes += depth_free_;
    // Only the pieces that may lie in front of the hemicube plane (PieceBvh; the others would
    // be found wholly behind it by cull()): their vertex slots (piece corners, T-vertices)
    // relative to the eye in the local frame, subtracted in double before they become floats:
    // far-off coordinates (1e5) keep full float precision near the eye. Equal world positions
    // give bitwise equal vertices. Other slots keep stale values that no index list names.
    if (++visit_stamp_ == 0) {
        std::fill(visit_.begin(), visit_.end(), 0u);
        visit_stamp_ = 1;
    }
    const std::size_t in_front = pieces_.bvh.mark_in_front(eye, fr.normal, visit_, visit_stamp_);
    st.pieces_behind += scene_.grids.size() - in_front;
    const Vec3* pos = pieces_.pos.data();
    for (std::size_t g = 0; g < scene_.grids.size(); ++g) {
        if (visit_[g] != visit_stamp_) continue;
        for (std::size_t s = pieces_.first[g]; s < pieces_.first[g + 1]; ++s) {
            const Vec3 d = pos[s] - eye;
            float* out = &local_[s * 3];
            out[0] = static_cast<float>(glm::dot(d, fr.tangent));
            out[1] = static_cast<float>(glm::dot(d, fr.bitangent));
            out[2] = static_cast<float>(glm::dot(d, fr.normal));
        }
    }
    cull(st);
    st.prepare_seconds += watch.seconds();
    watch.restart();

    gl.BindFramebuffer(GL_FRAMEBUFFER, (res == Res::full ? target_ : half_target_).fbo.id());
    const std::array<FaceSpec, 5>& faces = res == Res::full ? face_m_ : half_face_m_;
    const double near = HemicubeRowProvider::kNear * pa.size;
    {
        // std140: four dvec4s (item.vert's HemicubeEye); the shader makes local_'s floats itself.
        const double eye_frame[16] = {eye.x, eye.y, eye.z, 0, fr.tangent.x, fr.tangent.y, fr.tangent.z, 0,
                                      fr.bitangent.x, fr.bitangent.y, fr.bitangent.z, 0, fr.normal.x, fr.normal.y, fr.normal.z, 0};
        gl.BindBuffer(GL_UNIFORM_BUFFER, eye_ubo_.id());
        gl.BufferSubData(GL_UNIFORM_BUFFER, 0, sizeof(eye_frame), eye_frame);
        st.upload_vertex_bytes += sizeof(eye_frame);
    }
    if (opt_.occlusion_culling && drawn_.size() >= kOcclusionMinPieces) occlude(faces, near, res, eye, fr, st);
    build_lists(false, &st);
    upload_lists(st);
    const GLuint zero_id[4] = {0, 0, 0, 0};
    const GLfloat zero_depth = 0.0f;  // reversed Z: 0 is infinitely far
    // Inside a closed enclosure every pixel is drawn (Enclosure::closed): no clear.
    if (!(enclosure_now_ && pieces_.enclosure.closed)) gl.ClearBufferuiv(GL_COLOR, 0, zero_id);
    // Only depth-tested pieces read depth: a hemicube that sees the enclosure alone (inside an
    // empty room) needs no depth buffer at all.
    if (!depth_free_ && std::any_of(lists_, lists_ + kEnclosureLists, [](const auto& l) { return !l.empty(); }))
        gl.ClearBufferfv(GL_DEPTH, 0, &zero_depth);
    draw_lists(faces, near, 2, depth_free_);
    gl.Finish();
    st.draw_seconds += watch.seconds();
    watch.restart();
    const HemicubeLayout& lay = layout_of(res);
    gl.ReadPixels(0, 0, lay.atlas_width(), lay.atlas_height(), GL_RED_INTEGER, GL_UNSIGNED_INT,
                  (res == Res::full ? ids_ : half_ids_).data());
    gl::check_gl(gl, "hemicube rendering");
    st.readback_seconds += watch.seconds();
    st.hemicubes += 1;
}

// Row p: one hemicube at the centroid (no points), or the weighted sum of sub-hemicubes at the
// sender points the request gives (the patch's quadrature points, or points on the exposed part
// of a cut sender: the caller's rule), each with its own visibility.
void Worker::row(std::uint32_t p, std::span<const Vec3> points, std::span<const double> weights, SparseRow& out,
                 HemicubeStats& st) {
    if (test_fail_ != 0) fail_for_test(test_fail_, p);
    if (points.empty()) {
        hemicube_row(p, scene_.patches[p].centroid, Res::full, out, st);
        return;
    }
    FFCUBE_CHECK_MSG(points.size() == weights.size(), "Worker::row: one weight per sender point");
    begin_row();
    accumulate_points(p, points, weights, Res::half, st);
    take_row(out, st);
}

void Worker::begin_row() {
    ++epoch_;
    touched_.clear();
}

void Worker::hemicube_row(std::uint32_t p, const Vec3& at, Res res, SparseRow& out, HemicubeStats& st) {
    begin_row();
    render(p, at, res, st);
    accumulate(p, 1.0, res, st);
    take_row(out, st);
}

// The weighted sum of half-resolution hemicubes at the points into acc_: four of them cost about
// one full hemicube, and their average has about the pixel noise of one (each has twice the
// relative noise).
void Worker::accumulate_points(std::uint32_t p, std::span<const Vec3> points, std::span<const double> weights, Res res,
                               HemicubeStats& st) {
    for (std::size_t q = 0; q < points.size(); ++q) {
        render(p, points[q], res, st);
        accumulate(p, weights[q], res, st);
    }
}

// The row made in acc_ over touched_, sorted by column. A dense row (m touched of n columns, m
// log2 m above n) is listed by one pass over stamp_ in column order instead of sorting touched_:
// the same columns in the same order (each touched once), at n compares against m log m (at 5k
// patches, N = 128, about 1,600 of 5,010 columns: sorting was 3% of a worker's CPU).
//
// Dense scenes (dense_) keep no touched_ list: acc_ is zero outside a row (the row's entries are
// zeroed as they are taken) and every entry added is positive (ΔF sums, positive weights), so
// the row is acc_'s nonzero entries, found by one pass.
void Worker::take_row(SparseRow& out, HemicubeStats& st) {
    Stopwatch watch;
    if (dense_) {
        out.clear();
        for (std::uint32_t j = 0; j < acc_.size(); ++j) {
            if (acc_[j] == 0.0) continue;
            out.col.push_back(j);
            out.val.push_back(acc_[j]);
            acc_[j] = 0.0;
        }
        st.accumulate_seconds += watch.seconds();
        return;
    }
    const std::size_t m = touched_.size(), n = stamp_.size();
    if (m * static_cast<std::size_t>(std::bit_width(m)) > n) {
        std::size_t k = 0;
        for (std::uint32_t j = 0; j < n; ++j)
            if (stamp_[j] == epoch_) touched_[k++] = j;
        FFCUBE_CHECK(k == m);
    } else {
        std::sort(touched_.begin(), touched_.end());
    }
    out.clear();
    out.col.reserve(touched_.size());
    out.val.reserve(touched_.size());
    for (std::uint32_t j : touched_) {
        out.col.push_back(j);
        out.val.push_back(acc_[j]);
    }
    st.accumulate_seconds += watch.seconds();
}

// The column of a pixel's id (id − 1). An id past the last patch means a broken patch lookup
// (shader or pieces): a bug, stopped here instead of writing past the row's arrays.
inline __attribute__((always_inline)) std::uint32_t Worker::column_of(std::uint32_t p, std::size_t k,
                                                                     std::uint32_t id) const {
    const std::uint32_t j = id - 1;
    if (j >= stamp_.size()) bad_id(p, k, id);
    return j;
}

[[noreturn]] __attribute__((noinline)) void Worker::bad_id(std::uint32_t p, std::size_t k, std::uint32_t id) const {
    throw_internal("id - 1 < patches", __FILE__, __LINE__,
                   fmt::format("hemicube of patch {}: pixel {} shows id {}, past the last patch {}", p, k, id, stamp_.size()));
}

// Starts column j of the row being made (epoch_) at 0 the first time a pixel shows it. The test
// is inlined into the accumulation's loop over runs; the first touch is a call.
inline __attribute__((always_inline)) void Worker::touch(std::uint32_t j) {
    if (!dense_ && stamp_[j] != epoch_) first_touch(j);
}

__attribute__((noinline)) void Worker::first_touch(std::uint32_t j) {
    stamp_[j] = epoch_;
    acc_[j] = 0.0;
    touched_.push_back(j);
}

// Calls f(a, b, id, ΔF) for every run [a, b) of pixels of one id within a face's row of the
// atlas `ids` (indices into ids), ΔF summed over the run (HemicubeLayout::run_sum). A patch covers
// runs of neighbouring pixels: the run starts are found four pixels at a time
// (hemicube/runs.hpp) and a run's ΔF costs one subtraction, so the per-pixel work is one compare,
// not an addition chained to the previous one and a branch that mispredicts at every run's end
// (at N = 256: 2.5 ns a pixel before, 1.1 after; docs/benchmarks.md, "The rows' accumulation").
template <class F>
void Worker::for_each_id_run(const std::vector<std::uint32_t>& ids, const HemicubeLayout& lay, F&& f) {
    const std::size_t width = static_cast<std::size_t>(lay.atlas_width());
    for (std::size_t y = 0; y * width < ids.size(); ++y) {
        const std::size_t row = y * width;
        for (const HemicubeLayout::RowSegment& seg : lay.row_segments(static_cast<int>(y))) {
            const std::size_t len = seg.end - seg.begin, first = row + seg.begin;
            run_bits_.resize((len + 63) / 64);
            mark_run_starts(std::span<const std::uint32_t>(ids.data() + first, len), run_bits_.data());
            for_each_run(run_bits_.data(), len, [&](std::size_t a, std::size_t b) __attribute__((always_inline)) {
                f(first + a, first + b, ids[first + a], lay.run_sum(seg, seg.begin + a, seg.begin + b));
            });
        }
    }
}

// Adds weight × ΔF of every pixel of the rendered atlas to the row being made (epoch_).
void Worker::accumulate(std::uint32_t p, double weight, Res res, HemicubeStats& st) {
    Stopwatch watch;
    const HemicubeLayout& lay = layout_of(res);
    const std::vector<std::uint32_t>& ids = res == Res::full ? ids_ : half_ids_;
    const std::uint32_t self = p + 1;
    double back = 0.0, miss = 0.0;
    for_each_id_run(ids, lay, [&](std::size_t a, std::size_t b, std::uint32_t id, double s) __attribute__((always_inline)) {
        if (id == self) {
            st.self_hits += b - a;
        } else if (id == 0) {
            miss += s;
        } else if (id == kBackFace) {
            back += s;
        } else {
            const std::uint32_t j = column_of(p, a, id);
            if (occluders_) seen_[piece_of_[j]] = seen_stamp_;
            touch(j);
            acc_[j] += weight * s;
        }
    });
    end_seen();
    st.back_face_units += HemicubeStats::weight_units(weight * back);
    st.miss_units += HemicubeStats::weight_units(weight * miss);
    st.accumulate_seconds += watch.seconds();
}

// The pieces this hemicube showed are the next one's occluders (occlude()).
void Worker::end_seen() {
    last_stamp_ = seen_stamp_;
    if (++seen_stamp_ == 0) {
        std::fill(seen_.begin(), seen_.end(), 0u);
        last_stamp_ = 0;  // no occluders for the next hemicube
        seen_stamp_ = 1;
    }
}

void LocalEngine::start() {
    ctx_->make_current();
    worker_ = std::make_unique<Worker>(*ctx_, *scene_, *pieces_, layout_, opt_);
}

void LocalEngine::set_scene(const Scene& scene, const ScenePieces& pieces) {
    scene_ = &scene;
    pieces_ = &pieces;
    stale_ = true;
}

Worker& LocalEngine::worker() {
    if (stale_) {
        worker_.reset();  // its GL objects go while the context is current, on this thread
        worker_ = std::make_unique<Worker>(*ctx_, *scene_, *pieces_, layout_, opt_);
        stale_ = false;
    }
    return *worker_;
}

void LocalEngine::row(std::uint32_t p, std::span<const Vec3> points, std::span<const double> weights, SparseRow& out,
                      HemicubeStats& st) {
    worker().row(p, points, weights, out, st);
}

void LocalEngine::item_buffer(std::uint32_t p, std::vector<std::uint32_t>& out) {
    HemicubeStats ignored;
    Worker& w = worker();
    w.render(p, ignored);
    out = w.ids();
}

void LocalEngine::stop() {
    worker_.reset();
    ctx_->release_current();
}

}  // namespace ffcube
