// The drawing half of the GL worker (hemicube_worker.hpp): which pieces a hemicube draws (culling
// by the frustum and by occluders), their index lists, and the draw calls. The other half
// (hemicube_worker.cpp) makes the worker, renders and turns the item buffers into rows.
#include <fmt/format.h>
#include <glm/geometric.hpp>

#include <algorithm>
#include <cstring>

#include "ffcube/core/error.hpp"
#include "ffcube/core/timer.hpp"
#include "ffcube/hemicube/frame.hpp"
#include "ffcube/hemicube/outcode.hpp"
#include "gl/gl_api.hpp"
#include "gl/hemicube_worker.hpp"

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

}  // namespace ffcube
