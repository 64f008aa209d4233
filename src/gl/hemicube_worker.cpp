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
#include "ffcube/geometry/quadrature.hpp"
#include "ffcube/hemicube/frame.hpp"
#include "ffcube/hemicube/outcode.hpp"
#include "ffcube/hemicube/runs.hpp"
#include "gl/gl_api.hpp"
#include "gl/sample_agreement.hpp"
#include "gl/shaders.hpp"

namespace ffcube {

namespace {

// Column-major 4×4 for glUniformMatrix4fv: reversed-Z, infinite far plane, near at 'near'
// (eye units), times the face's view rotation (rows right, up, -forward).
std::array<float, 16> face_matrix(const FaceSpec& f, double near) {
    const FaceFrustum& fr = f.frustum;
    // Projection rows (acting on eye coordinates):
    //   x' = 2/(r-l) x + (r+l)/(r-l) z,  y' = 2/(t-b) y + (t+b)/(t-b) z,  z' = near,  w' = -z
    // so NDC depth = near / distance: with glClipControl(ZERO_TO_ONE) and GL_GREATER, float depth
    // keeps about 7 significant digits at every distance.
    const double P[4][4] = {{2 / (fr.right - fr.left), 0, (fr.right + fr.left) / (fr.right - fr.left), 0},
                            {0, 2 / (fr.top - fr.bottom), (fr.top + fr.bottom) / (fr.top - fr.bottom), 0},
                            {0, 0, 0, near},
                            {0, 0, -1, 0}};
    const Vec3 rows[3] = {f.right, f.up, -f.forward};
    double V[4][4] = {};
    for (int r = 0; r < 3; ++r) {
        V[r][0] = rows[r].x;
        V[r][1] = rows[r].y;
        V[r][2] = rows[r].z;
    }
    V[3][3] = 1;
    std::array<float, 16> m{};
    for (int r = 0; r < 4; ++r)
        for (int c = 0; c < 4; ++c) {
            double s = 0;
            for (int k = 0; k < 4; ++k) s += P[r][k] * V[k][c];
            m[static_cast<std::size_t>(c * 4 + r)] = static_cast<float>(s);
        }
    return m;
}

}  // namespace

// Hemicubes that list fewer pieces than this draw them all at once: occlusion culling's extra
// pass and depth readback would cost more than the pieces it can leave out.
constexpr std::size_t kOcclusionMinPieces = 128;
// Occluders chosen by angular size (occlude()), besides those the last hemicube showed.
constexpr std::size_t kOccluderCount = 32;

int half_resolution(int n) { return n / 2 >= 8 && (n / 2) % 2 == 0 ? n / 2 : n; }
int fine_resolution(int n, HemicubeOptions::FineSubResolution mode) {
    using M = HemicubeOptions::FineSubResolution;
    const int m = mode == M::quarter ? n / 4 : mode == M::three_eighths ? 3 * n / 8 : 0;
    const bool exact = mode == M::quarter ? n % 4 == 0 : n % 8 == 0;
    return mode != M::half && exact && m >= 8 && m % 2 == 0 ? m : half_resolution(n);
}

bool range_limits_sub_hemicubes(const HemicubeOptions& opt, std::size_t pieces, int n) {
    return opt.sub_hemicube_range == HemicubeOptions::SubHemicubeRange::automatic &&
           pieces >= opt.sub_hemicube_range_min_pieces && 2 * half_resolution(n) == n;
}

Worker::Worker(GlContext& ctx, const Scene& scene, const ScenePieces& pieces, const HemicubeLayout& layout,
       const HemicubeOptions& opt)
    : gl_(ctx.api()), scene_(scene), pieces_(pieces), layout_(layout), half_layout_(half_resolution(layout.resolution())),
      quarter_layout_(fine_resolution(layout.resolution(), opt.fine_sub_resolution)),
      opt_(opt) {
    const gl::Api& gl = gl_;
    // The fragment shader specialised to the piece kinds of the scene: llvmpipe runs both
    // sides of a branch under a mask, so a path no piece takes still costs every pixel.
    std::string frag(shaders::item_frag);
    const std::size_t eol = frag.find('\n') + 1;
    const std::string kinds = fmt::format("#define HAS_TRIANGLES {}\n#define HAS_BILINEAR {}\n", pieces.has_kind[3] ? 1 : 0,
                                          pieces.has_kind[4] ? 1 : 0);
    world_positions_ = opt.vertex_upload == HemicubeOptions::VertexUpload::once;
    const std::string positions = world_positions_ ? "#define WORLD_POSITIONS 1\n" : "";
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
    if (opt.fine_sub_resolution != HemicubeOptions::FineSubResolution::half)
        quarter_target_ = gl::make_item_target(gl, quarter_layout_.atlas_width(), quarter_layout_.atlas_height());
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
    if (world_positions_) {
        // The vertex slots' world positions, once (item.vert, WORLD_POSITIONS).
        static_assert(sizeof(Vec3) == 3 * sizeof(double));
        gl.BufferData(GL_ARRAY_BUFFER, static_cast<GLsizeiptr>(std::max<std::size_t>(slots, 1) * sizeof(Vec3)),
                      slots ? pieces.pos.data() : nullptr, GL_STATIC_DRAW);
        gl.VertexAttribLPointer(0, 3, GL_DOUBLE, sizeof(Vec3), nullptr);
        eye_ubo_ = gl::make_buffer(gl);
        gl.BindBuffer(GL_UNIFORM_BUFFER, eye_ubo_.id());
        gl.BufferData(GL_UNIFORM_BUFFER, 16 * sizeof(double), nullptr, GL_STREAM_DRAW);
        gl.BindBufferBase(GL_UNIFORM_BUFFER, 1, eye_ubo_.id());
    } else {
        gl.BufferData(GL_ARRAY_BUFFER, static_cast<GLsizeiptr>(std::max<std::size_t>(slots, 1) * 3 * sizeof(float)),
                      nullptr, GL_STREAM_DRAW);
        gl.VertexAttribPointer(0, 3, GL_FLOAT, GL_FALSE, 3 * sizeof(float), nullptr);
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
        quarter_face_m_[f] = quarter_layout_.faces()[f];
    }
    half_ids_.resize(static_cast<std::size_t>(half_layout_.atlas_width()) * half_layout_.atlas_height());
    quarter_ids_.resize(static_cast<std::size_t>(quarter_layout_.atlas_width()) * quarter_layout_.atlas_height());
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
    // Range-limited rows only: the piece boxes (every vertex slot: corners and T-vertices).
    range_on_ = range_limits_sub_hemicubes(opt, scene.grids.size(), layout.resolution());
    if (range_on_) {
        vis_.resize(half_ids_.size());
        box_lo_.assign(scene.grids.size(), Vec3(0.0));
        box_hi_.assign(scene.grids.size(), Vec3(0.0));
        for (std::size_t g = 0; g < scene.grids.size(); ++g) {
            Vec3 lo(INFINITY), hi(-INFINITY);
            for (std::size_t s = pieces.first[g]; s < pieces.first[g + 1]; ++s) {
                lo = glm::min(lo, pieces.pos[s]);
                hi = glm::max(hi, pieces.pos[s]);
            }
            box_lo_[g] = lo;
            box_hi_[g] = hi;
            scene_lo_ = g == 0 ? lo : glm::min(scene_lo_, lo);
            scene_hi_ = g == 0 ? hi : glm::max(scene_hi_, hi);
        }
    }
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
        // Range-limited rows (sample_range_limited): a sub-hemicube draws the pieces whose box
        // comes within range_r_ of its eye, the centroid's hemicube those not wholly near.
        if (range_mode_ != RangeDraw::all) {
            bool out;
            if (range_mode_ == RangeDraw::within_eye) {
                const Vec3 q = glm::clamp(eye, box_lo_[g], box_hi_[g]);
                out = glm::length(q - eye) > range_r_;
            } else {
                out = piece_near(static_cast<std::uint32_t>(g));
            }
            if (out) {
                visit_[g] = 0;  // never equal to visit_stamp_ (≥ 1)
                ++st.pieces_out_of_range;
                continue;
            }
        }
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

    gl.BindFramebuffer(GL_FRAMEBUFFER,
                       (res == Res::full ? target_ : res == Res::half ? half_target_ : quarter_target_).fbo.id());
    const std::array<FaceSpec, 5>& faces = res == Res::full ? face_m_ : res == Res::half ? half_face_m_ : quarter_face_m_;
    const double near = HemicubeRowProvider::kNear * pa.size;
    if (world_positions_) {
        // std140: four dvec4s (item.vert's HemicubeEye); the shader makes local_'s floats itself.
        const double eye_frame[16] = {eye.x, eye.y, eye.z, 0, fr.tangent.x, fr.tangent.y, fr.tangent.z, 0,
                                      fr.bitangent.x, fr.bitangent.y, fr.bitangent.z, 0, fr.normal.x, fr.normal.y, fr.normal.z, 0};
        gl.BindBuffer(GL_UNIFORM_BUFFER, eye_ubo_.id());
        gl.BufferSubData(GL_UNIFORM_BUFFER, 0, sizeof(eye_frame), eye_frame);
        st.upload_vertex_bytes += sizeof(eye_frame);
    } else {
        gl.BindBuffer(GL_ARRAY_BUFFER, vbo_.id());
        gl.BufferSubData(GL_ARRAY_BUFFER, 0, static_cast<GLsizeiptr>(local_.size() * sizeof(float)), local_.data());
        st.upload_vertex_bytes += local_.size() * sizeof(float);
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
                  (res == Res::full ? ids_ : res == Res::half ? half_ids_ : quarter_ids_).data());
    gl::check_gl(gl, "hemicube rendering");
    st.readback_seconds += watch.seconds();
    st.hemicubes += 1;
}

// Row p: one hemicube at the centroid, or the average of sub-hemicubes at the patch's 2 × 2
// quadrature points (geometry/quadrature.hpp, the points the near-field correction's sender
// quadrature uses; 4 × 4 for a sender with an occluder touching it), each with its own visibility.
void Worker::row(std::uint32_t p, SparseRow& out, HemicubeStats& st, int sub_points) {
    if (test_fail_ != 0) fail_for_test(test_fail_, p);
    if (sub_points >= 2 && sample_exposed(p, st)) {
        take_row(out, st);
        return;
    }
    if (sub_points >= 4 && opt_.adaptive_sampling) {
        if (sample_adaptive(p, out, st)) {
            ++st.fine_rows_stopped;
            ++st.sampled_rows;
            return;
        }
        ++st.fine_rows_refined;
    }
    if (sub_points < 2) {
        hemicube_row(p, scene_.patches[p].centroid, Res::full, out, st);
        return;
    }
    begin_row();
    if (range_applies(p)) {
        sample_range_limited(p, sub_points, st);
        ++st.range_limited_rows;
    } else {
        sample(p, sub_points, st);
    }
    ++st.sampled_rows;
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

void Worker::sample(std::uint32_t p, int sub_points, HemicubeStats& st) {
    const auto v = scene_.patch_vertices(p);
    patch_quadrature(std::span<const Vec3>(v.data(), scene_.patches[p].count), sub_points, points_, weights_);
    const bool quarter = sub_points >= 4 && opt_.fine_sub_resolution != HemicubeOptions::FineSubResolution::half;
    accumulate_points(p, quarter ? Res::quarter : Res::half, st);
}

// The weighted sum of half-resolution hemicubes at points_ (weights_) into acc_: four of them cost
// about one full hemicube, and their average has about the pixel noise of one (each has twice the
// relative noise).
void Worker::accumulate_points(std::uint32_t p, Res res, HemicubeStats& st) {
    for (std::size_t q = 0; q < points_.size(); ++q) {
        render(p, points_[q], res, st);
        accumulate(p, weights_[q], res, st);
    }
}

bool Worker::sample_exposed(std::uint32_t p, HemicubeStats& st) {
    if (!exposed_) exposed_ = std::make_unique<ExposedPoints>(scene_);
    if (!exposed_->rule(p, points_, weights_)) return false;
    begin_row();
    accumulate_points(p, Res::half, st);
    ++st.sampled_rows;
    ++st.partly_enclosed_rows;
    return true;
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

bool Worker::sample_adaptive(std::uint32_t p, SparseRow& out, HemicubeStats& st) {
    const auto v = scene_.patch_vertices(p);
    patch_quadrature(std::span<const Vec3>(v.data(), scene_.patches[p].count), 2, points_, weights_);
    sample_rows_.resize(points_.size());
    for (std::size_t q = 0; q < points_.size(); ++q) hemicube_row(p, points_[q], Res::half, sample_rows_[q], st);
    hemicube_row(p, scene_.patches[p].centroid, Res::half, centre_row_, st);
    Stopwatch watch;
    SampleAgreementOptions o;
    const double n = half_layout_.resolution();
    o.pixel_delta_ff = 4.0 / (std::numbers::pi * n * n);
    const SampleAgreement a = judge_samples(scene_, p, points_, weights_, sample_rows_, centre_row_, o, out);
    st.accumulate_seconds += watch.seconds();
    return !a.refine;
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
    const std::vector<std::uint32_t>& ids = res == Res::full ? ids_ : res == Res::half ? half_ids_ : quarter_ids_;
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
    st.back_face_weight += weight * back;
    st.miss_weight += weight * miss;
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

// Range-limited sub-hemicubes (HemicubeOptions::sub_hemicube_range; docs/accuracy.md). At city
// scale a sub-hemicube is geometry-bound: sixteen of them draw the visible city sixteen times
// though each has few pixels. Here the row is split at a range R = sub_hemicube_range_k × size
// around the sender's centroid c (r: the largest distance from c to an eye, the sender's radius
// plus the eye offset):
//  - a piece is near when its box lies wholly within R − r of c, so within R of every eye;
//  - each sub-hemicube draws only the pieces whose box comes within R of its eye. Every near
//    piece is drawn, and so is everything in front of a point of it (nearer than that point,
//    so within R): a near entry's pixels are what the full sub-hemicube shows, and near entries
//    take the sub-hemicube average exactly as a plain row;
//  - one full-resolution hemicube at c draws every piece that is not near (what lies beyond the
//    near pieces, their occlusion among themselves as c sees it); a far entry j gets
//    Σ over its pixels of ΔF × v, v the weight of the sub-hemicubes whose pixel in that
//    direction (the half-resolution pixel at half the coordinates: same frame, same rotation,
//    hemicube/layout.hpp's atlas scales by exactly 2) shows nothing or a piece that is not near,
//    i.e. that sees past the near pieces.
// What v misses is the parallax of what is not near between the eyes: a far piece at distance
// d ≥ R − r shifts by at most r/(R − r) radians (about 1/(2k) at k = R/size, since r ≈ size/√2
// on a square sender: 0.03 rad at k = 24, about one half-resolution pixel of N = 128 at the top
// face's centre, 2/64 rad). Straddling pieces (near part within R, far part beyond) are drawn
// by both and counted by the centroid's hemicube, with their larger parallax: measured in
// docs/benchmarks.md ("Range-limited sub-hemicubes").
bool Worker::piece_near(std::uint32_t g) const {
    const Vec3 d = glm::max(glm::abs(box_lo_[g] - range_centre_), glm::abs(box_hi_[g] - range_centre_));
    return glm::length(d) <= range_near_;
}

bool Worker::range_applies(std::uint32_t p) {
    if (!range_on_) return false;
    const Patch& pa = scene_.patches[p];
    const auto v = scene_.patch_vertices(p);
    double r = 0;
    for (std::size_t k = 0; k < pa.count; ++k) r = std::max(r, glm::length(v[k] - pa.centroid));
    // |eye − c| ≤ |point − c| + eye offset (the offset is along the normal).
    r += HemicubeRowProvider::kEyeOffset * pa.size;
    range_centre_ = pa.centroid;
    range_r_ = opt_.sub_hemicube_range_k * pa.size;
    // A relative margin against rounding: a piece called near is drawn by every sub-hemicube.
    range_near_ = range_r_ * (1 - 1e-9) - r;
    if (!(range_near_ > 0)) return false;
    // The whole scene near: every sub-hemicube would draw everything anyway.
    const Vec3 d = glm::max(glm::abs(scene_lo_ - range_centre_), glm::abs(scene_hi_ - range_centre_));
    if (!(glm::length(d) > range_near_)) return false;
    // Only where it pays: the sub-hemicubes draw the pieces within R + r of the centroid (a box
    // test, the same for every thread), the extra full hemicube about all the others; a row
    // whose range holds more than sub_hemicube_range_max_share of the pieces stays plain.
    std::size_t within = 0;
    const double reach = range_r_ + r;
    for (std::size_t g = 0; g < box_lo_.size(); ++g) {
        const Vec3 q = glm::clamp(range_centre_, box_lo_[g], box_hi_[g]);
        within += glm::length(q - range_centre_) <= reach;
    }
    return static_cast<double>(within) <= opt_.sub_hemicube_range_max_share * static_cast<double>(box_lo_.size());
}

void Worker::sample_range_limited(std::uint32_t p, int sub_points, HemicubeStats& st) {
    struct Reset {
        RangeDraw& mode;
        ~Reset() { mode = RangeDraw::all; }
    } reset{range_mode_};
    const auto v = scene_.patch_vertices(p);
    patch_quadrature(std::span<const Vec3>(v.data(), scene_.patches[p].count), sub_points, points_, weights_);
    std::fill(vis_.begin(), vis_.end(), 0.0);
    range_mode_ = RangeDraw::within_eye;
    for (std::size_t q = 0; q < points_.size(); ++q) {
        render(p, points_[q], Res::half, st);
        accumulate_range_near(p, weights_[q], st);
    }
    range_mode_ = RangeDraw::not_near;
    render(p, scene_.patches[p].centroid, Res::full, st);
    accumulate_range_far(p, st);
}

// A range-limited sub-hemicube: near entries as accumulate() adds them; a pixel that shows nothing
// or a piece that is not near adds the weight to vis_ (it sees past the near pieces); a back face
// blocks.
void Worker::accumulate_range_near(std::uint32_t p, double weight, HemicubeStats& st) {
    Stopwatch watch;
    const std::uint32_t self = p + 1;
    double back = 0.0;
    for_each_id_run(half_ids_, half_layout_, [&](std::size_t a, std::size_t b, std::uint32_t id, double s) {
        if (id == self) {
            st.self_hits += b - a;
            return;
        }
        if (id == kBackFace) {
            back += s;
            return;
        }
        if (id != 0) {
            const std::uint32_t j = column_of(p, a, id);
            const std::uint32_t g = piece_of_[j];
            seen_[g] = seen_stamp_;
            if (piece_near(g)) {
                touch(j);
                acc_[j] += weight * s;
                return;
            }
        }
        for (std::size_t k = a; k < b; ++k) vis_[k] += weight;
    });
    end_seen();
    st.back_face_weight += weight * back;
    st.accumulate_seconds += watch.seconds();
}

// The centroid's hemicube of what is not near: each pixel's ΔF times v of the half-resolution
// pixel in the same direction.
void Worker::accumulate_range_far(std::uint32_t p, HemicubeStats& st) {
    Stopwatch watch;
    const std::vector<double>& w = layout_.delta_ff();
    const std::uint32_t self = p + 1;
    double back = 0.0, miss = 0.0;
    const std::size_t width = static_cast<std::size_t>(layout_.atlas_width());
    const std::size_t half_width = static_cast<std::size_t>(half_layout_.atlas_width());
    const std::size_t npix = ids_.size();
    for (std::size_t k = 0; k < npix; ++k) {
        const std::uint32_t id = ids_[k];
        const double vk = vis_[(k / width / 2) * half_width + (k % width) / 2];
        if (id == 0) {
            miss += w[k] * vk;
        } else if (id == kBackFace) {
            back += w[k] * vk;
        } else if (id == self) {
            ++st.self_hits;
        } else {
            const std::uint32_t j = column_of(p, k, id);
            seen_[piece_of_[j]] = seen_stamp_;
            if (!(vk > 0)) continue;
            touch(j);
            acc_[j] += w[k] * vk;
        }
    }
    end_seen();
    st.back_face_weight += back;
    st.miss_weight += miss;
    st.accumulate_seconds += watch.seconds();
}

// Lists the pieces that may show (drawn_) with their faces: a piece goes to a face unless all its
// corners lie outside one of the face's frustum planes; pieces wholly behind the hemicube
// plane (z ≤ 0: this includes the patch's own piece and every piece coplanar with it) go
// nowhere. Corners suffice for pieces drawn with T-vertices too: those lie on the edges.
// Only the pieces render() marked as maybe in front are tested, in piece order (the draw
// order, which decides exact depth ties, is the same as when every piece was tested).
void Worker::cull(HemicubeStats& st) {
    drawn_.clear();
    const std::size_t ng = scene_.grids.size();
    st.pieces_considered += ng;
    for (std::size_t g = 0; g < ng; ++g) {
        if (visit_[g] != visit_stamp_) continue;
        ++st.pieces_tested;
        const std::uint32_t count = scene_.grids[g].count;
        const std::uint32_t base = pieces_.first[g];
        unsigned all = ~0u;
        bool behind = true;
        for (std::uint32_t k = 0; k < count; ++k) {
            const float* c = &local_[(base + k) * 3];
            const float x = c[0], y = c[1], z = c[2];
            behind = behind && z <= 0;
            all &= face_outcode(x, y, z);
        }
        if (behind) {
            ++st.pieces_behind;
            continue;
        }
        // x > y is bit 8 (-y > -x) and -x > y is bit 6 (-y > x); likewise for -y.
        constexpr unsigned kTop = 0b1111u;                                             // |x|,|y| ≤ z
        constexpr unsigned kPosX = (1u << 4) | (1u << 5) | (1u << 6) | (1u << 9);    // |y| ≤ x, 0 ≤ z ≤ x
        constexpr unsigned kNegX = (1u << 4) | (1u << 7) | (1u << 8) | (1u << 10);   // |y| ≤ -x, 0 ≤ z ≤ -x
        constexpr unsigned kPosY = (1u << 4) | (1u << 6) | (1u << 8) | (1u << 11);   // |x| ≤ y, 0 ≤ z ≤ y
        constexpr unsigned kNegY = (1u << 4) | (1u << 5) | (1u << 7) | (1u << 12);   // |x| ≤ -y, 0 ≤ z ≤ -y
        constexpr unsigned masks[5] = {kTop, kPosX, kNegX, kPosY, kNegY};
        // Front-facing: the eye (the origin) lies in front of the piece's plane, whose normal
        // (c1 − c0) × (c2 − c0) points to its front (corners CCW from the front).
        const float* c0 = &local_[base * 3];
        const float* c1 = c0 + 3;
        const float* c2 = c0 + 6;
        const double e1[3] = {double(c1[0]) - c0[0], double(c1[1]) - c0[1], double(c1[2]) - c0[2]};
        const double e2[3] = {double(c2[0]) - c0[0], double(c2[1]) - c0[1], double(c2[2]) - c0[2]};
        const double nrm[3] = {e1[1] * e2[2] - e1[2] * e2[1], e1[2] * e2[0] - e1[0] * e2[2], e1[0] * e2[1] - e1[1] * e2[0]};
        const bool back = nrm[0] * c0[0] + nrm[1] * c0[1] + nrm[2] * c0[2] > 0;
        if (back && pieces_.has_twin[g]) continue;  // its twin's front covers it (find_twins)
        std::uint8_t faces = 0;
        for (std::size_t f = 0; f < 5; ++f) {
            if (all & masks[f])
                ++st.pieces_culled[f];
            else
                faces = static_cast<std::uint8_t>(faces | (1u << f));
        }
        if (faces != 0) drawn_.push_back({static_cast<std::uint32_t>(g), faces, back});
    }
}

// The index lists of drawn_'s pieces per face and pass, in piece order (the draw order, which
// decides exact depth ties): every piece, or (occluders_only) the front pieces the last hemicube
// showed. st: counts the drawn pieces per face.
//
// Inside the enclosure (enclosure_now_), its front pieces go to their own lists, in reverse piece
// order: drawn first without the depth test, where they never overlap (hemicube/pieces.hpp,
// Enclosure), the last drawn is the first piece, as the depth test's GL_GREATER let the first
// drawn win an exact tie (two pieces with the same corners). When no piece needs the depth test
// at all (depth_free_: Enclosure::inner_flat), the other lists are made in reverse order too.
void Worker::build_lists(bool occluders_only, HemicubeStats* st) {
    for (auto& l : lists_) l.clear();
    const bool split = enclosure_now_ && !occluders_only;
    const bool reverse_all = split && depth_free_;
    const auto in_enclosure = [&](const Drawn& d) { return split && !d.back && pieces_.enclosure.piece[d.g]; };
    const auto list0 = [&](const Drawn& d) -> std::size_t {
        if (d.back) return kBackLists;
        const std::size_t group = 5 * group_of_kind_[pieces_.gpu[d.g].count];
        return in_enclosure(d) ? kEnclosureLists + group : group;
    };
    if (!reverse_all)
        for (const Drawn& d : drawn_) {
            if (occluders_only && !d.occluder) continue;
            if (!in_enclosure(d)) add_to_lists(d, list0(d), st);
        }
    if (!split) return;
    for (auto it = drawn_.rbegin(); it != drawn_.rend(); ++it) {
        const bool enclosed = in_enclosure(*it);
        if (!enclosed && !reverse_all) continue;
        add_to_lists(*it, list0(*it), st);
        if (enclosed && st) st->enclosure_pieces_drawn += static_cast<std::uint64_t>(std::popcount(it->faces));
    }
}

// Piece d's triangles into the lists [list0, list0 + 5) of the faces it goes to.
void Worker::add_to_lists(const Drawn& d, std::size_t list0, HemicubeStats* st) {
    const std::uint32_t base = pieces_.first[d.g];
    const std::uint32_t count = scene_.grids[d.g].count;
    const std::uint32_t* tri_begin = pieces_.tris.data() + pieces_.tri_first[d.g];
    const std::uint32_t* tri_end = pieces_.tris.data() + pieces_.tri_first[d.g + 1];
    for (std::size_t f = 0; f < 5; ++f) {
        if (!(d.faces & (1u << f))) continue;
        if (st) ++st->pieces_drawn[f];
        auto& l = lists_[list0 + f];
        if (tri_begin == tri_end) {
            l.insert(l.end(), {base, base + 1, base + 2});
            if (count == 4) l.insert(l.end(), {base, base + 2, base + 3});
        } else {
            l.insert(l.end(), tri_begin, tri_end);  // a polygon with T-vertices
        }
    }
}

// The index lists back to back into the element buffer.
void Worker::upload_lists(HemicubeStats& st) {
    all_idx_.clear();
    for (const auto& l : lists_) all_idx_.insert(all_idx_.end(), l.begin(), l.end());
    gl_.BufferData(GL_ELEMENT_ARRAY_BUFFER, static_cast<GLsizeiptr>(std::max<std::size_t>(all_idx_.size(), 1) * 4),
                   all_idx_.data(), GL_STREAM_DRAW);
    st.upload_index_bytes += all_idx_.size() * sizeof(std::uint32_t);
}

// Draws the uploaded lists into the bound target: the front pass, then (passes 2) the back one;
// depth_free: all of it without the depth test (render(), inside an inner_flat enclosure).
void Worker::draw_lists(const std::array<FaceSpec, 5>& faces, double near, int passes, bool depth_free) {
    const gl::Api& gl = gl_;
    // Front-facing pieces first, then back-facing ones pushed 64 depth units farther
    // (reversed Z: negative offset), so a two-sided plate made of two one-sided faces back to
    // back shows its front side, never the back of the other (no z-fighting; GL_GREATER also
    // lets the first drawn win exact ties; 4 units were too few for the two faces' rounding,
    // measured). No slope factor: a back face seen edge-on (a wall standing on the sender's
    // plate) has a huge depth slope, and slope × 1 let what is behind it show through
    // (test Occluders.WallSeenEdgeOnFromBothSidesBlocksEverything: 508 leaking pairs). Which side a fragment shows is the pass's (its program,
    // from cull()'s classification of the whole piece), not gl_FrontFacing: the rasterizer
    // snaps vertices to its subpixel grid, which can turn a sliver (a triangle seen almost
    // edge-on, or a small one beside a T-vertex) over, and a front piece would then show a
    // back-face pixel.
    // The lists lie back to back in the element buffer (upload_lists), in lists_'s order.
    std::array<std::size_t, kLists> first{};
    for (std::size_t k = 1; k < kLists; ++k) first[k] = first[k - 1] + lists_[k - 1].size();
    const auto draw = [&](std::size_t list0, GLint u_face) {
        for (std::size_t f = 0; f < 5; ++f) {
            const std::size_t count = lists_[list0 + f].size();
            if (count == 0) continue;
            const FaceSpec& fs = faces[f];
            const auto m = face_matrix(fs, near);
            gl.Viewport(fs.viewport.x, fs.viewport.y, fs.viewport.width, fs.viewport.height);
            gl.UniformMatrix4fv(u_face, 1, GL_FALSE, m.data());
            gl.DrawElements(GL_TRIANGLES, static_cast<GLsizei>(count), GL_UNSIGNED_INT,
                            reinterpret_cast<const void*>(first[list0 + f] * sizeof(std::uint32_t)));
        }
    };
    // The enclosure's pieces first, without the depth test (build_lists); programs_[0] last, as
    // the loops below expect.
    const bool enclosure = std::any_of(lists_ + kEnclosureLists, lists_ + kLists, [](const auto& l) { return !l.empty(); });
    if (enclosure || depth_free) gl.Disable(GL_DEPTH_TEST);
    if (enclosure) {
        for (std::uint32_t k = groups_; k-- > 0;) {
            if (groups_ > 1) gl.UseProgram(programs_[k].id());
            draw(kEnclosureLists + 5 * k, u_face_[k]);
        }
    }
    if (!depth_free) gl.Enable(GL_DEPTH_TEST);
    // Front pieces, a program per kind of piece (their lookups differ), then the back ones;
    // without the depth test, in reverse order (the lists are too), so the first still wins.
    for (std::uint32_t g = 0; g < groups_; ++g) {
        const std::uint32_t k = depth_free ? groups_ - 1 - g : g;
        if (groups_ > 1) gl.UseProgram(programs_[k].id());
        draw(5 * k, u_face_[k]);
    }
    if (passes > 1) {
        gl.Enable(GL_POLYGON_OFFSET_FILL);
        gl.PolygonOffset(0.0f, -64.0f);
        gl.UseProgram(back_program_.id());  // discards centres outside the piece (item.frag)
        draw(kBackLists, u_back_face_);
        gl.Disable(GL_POLYGON_OFFSET_FILL);
    }
    if (depth_free) gl.Enable(GL_DEPTH_TEST);
    if (passes > 1 || groups_ > 1) gl.UseProgram(programs_[0].id());
}

// Occlusion culling: the front pieces the worker's last hemicube showed are drawn first, depth
// only (in a street of a city: the facades around); the depth image is read back into a min-depth
// table per face (row minima), and a piece whose footprint on a face (hemicube/occlusion.hpp: the rectangle
// of its part that can make a fragment there, clipped to the near plane and the face's frustum)
// has every pixel nearer than the piece, by a margin, is left out of that face (the table
// answers exactly what a scan of the rectangle's pixels would). Exact: a piece left out has every fragment behind the
// depth those occluders leave, and the occluder that sets a pixel's depth is never left out
// itself (it would have to lie behind its own depth), so in the full drawing that follows every
// pixel ends at least as near, and the left-out piece could not have won one. The item buffer is
// bitwise the same as without (test OcclusionCulling.*); the choice of occluders only decides how much
// is left out, never what the hemicube shows, so rows do not depend on which worker drew what.
void Worker::occlude(const std::array<FaceSpec, 5>& faces, double near, Res res, const Vec3& eye, const HemicubeFrame& fr,
                     HemicubeStats& st) {
    const gl::Api& gl = gl_;
    // Occluders: front pieces the last hemicube showed (the same surroundings for the next
    // sub-hemicube of a row, often for the next row), and the kOccluderCount front pieces of the
    // largest angular size seen from here (bounding radius over the distance of the nearest
    // point of the bounding sphere: the facades around the eye).
    scores_.clear();
    for (std::size_t k = 0; k < drawn_.size(); ++k) {
        Drawn& d = drawn_[k];
        d.occluder = !d.back && seen_[d.g] == last_stamp_ && last_stamp_ != 0;
        if (d.back || d.occluder) continue;
        const Sphere& sp = sphere_[d.g];
        const double r = sp.radius, gap = glm::length(sp.centre - eye) - r;
        scores_.emplace_back(gap > 0 ? r / gap : INFINITY, static_cast<std::uint32_t>(k));
    }
    if (scores_.size() > kOccluderCount) {
        std::nth_element(scores_.begin(), scores_.begin() + kOccluderCount, scores_.end(),
                         [](const auto& a, const auto& b) { return a.first > b.first || (a.first == b.first && a.second < b.second); });
        scores_.resize(kOccluderCount);
    }
    for (const auto& [score, k] : scores_) drawn_[k].occluder = true;
    build_lists(true, nullptr);
    std::size_t occluders = 0;
    for (std::size_t k = 0; k < kBackLists; ++k) occluders += lists_[k].size();
    if (occluders == 0) return;
    upload_lists(st);
    const GLfloat zero_depth = 0.0f;
    gl.ClearBufferfv(GL_DEPTH, 0, &zero_depth);
    gl.ColorMask(GL_FALSE, GL_FALSE, GL_FALSE, GL_FALSE);
    draw_lists(faces, near, 1, false);  // depth only: the test on
    gl.ColorMask(GL_TRUE, GL_TRUE, GL_TRUE, GL_TRUE);
    const HemicubeLayout& lay = layout_of(res);
    gl.ReadPixels(0, 0, lay.atlas_width(), lay.atlas_height(), GL_DEPTH_COMPONENT, GL_FLOAT, depth_.data());
    const std::span<const float> depth(depth_.data(), static_cast<std::size_t>(lay.atlas_width()) * lay.atlas_height());
    for (std::size_t f = 0; f < 5; ++f) depth_rows_[f].build(depth, lay.atlas_width(), faces[f].viewport);
    // Whole nodes of the hierarchy first: a piece under a node hidden on a face is one the test
    // below would find hidden there too (hide_hidden_nodes), so it is left out without the test.
    unsigned open = 0;
    for (const Drawn& d : drawn_)
        if (!d.occluder) open |= d.faces;
    if (opt_.occlusion_nodes) st.nodes_occluded += hide_hidden_nodes(pieces_.bvh, faces, depth_rows_, eye, fr, near, open, hidden_);
    for (Drawn& d : drawn_) {
        if (d.occluder) continue;  // drawn, and in the depth image
        if (opt_.occlusion_nodes) {
            const unsigned by_node = hidden_.of(d.g) & d.faces;
            if (by_node != 0) {
                for (std::size_t f = 0; f < 5; ++f)
                    if (by_node & (1u << f)) {
                        ++st.pieces_occluded[f];
                        ++st.pieces_occluded_by_node;
                    }
                d.faces = static_cast<std::uint8_t>(d.faces & ~by_node);
                if (d.faces == 0) continue;
            }
        }
        const std::uint32_t base = pieces_.first[d.g];
        corners_.clear();
        for (std::uint32_t k = 0; k < scene_.grids[d.g].count; ++k) {
            const float* c = &local_[(base + k) * 3];
            corners_.emplace_back(c[0], c[1], c[2]);
        }
        for (std::size_t f = 0; f < 5; ++f) {
            if (!(d.faces & (1u << f))) continue;
            FaceFootprint fp = face_footprint(faces[f], corners_, near, false);
            if (hidden_behind(depth_rows_[f], fp)) {
                d.faces = static_cast<std::uint8_t>(d.faces & ~(1u << f));
                ++st.pieces_occluded[f];
            }
        }
    }
    ++st.occlusion_hemicubes;
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

void LocalEngine::row(std::uint32_t p, SparseRow& out, HemicubeStats& st, int sub_points) {
    worker().row(p, out, st, sub_points);
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
