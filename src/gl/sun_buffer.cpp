// Sunlit fractions by an orthographic item buffer along the sun (include/ffcube/gl/sun.hpp).
//
// The view: the plane ⟂ to the unit direction s towards the sun, with axes (e1, e2), and depth
// d = p·s (larger: nearer the sun). Every patch of the drawn scene (obstruction-only patches
// included) is drawn as one or two triangles with the ID 1 + its index; both faces, since a wall
// seen from behind shades what lies behind it as much as one seen from the front. The depth test
// keeps what is nearest the sun. A pixel showing patch i is a parcel of the beam that reaches i
// first, so i's sunlit projected area is (its pixels) × h², h the pixel's side, and
//     sunlit_fraction_i = pixels_i h² / (A_i cos θ_i),   cos θ_i = n_i·s > 0
// (0 where n_i·s ≤ 1e-9: a patch facing away, or edge-on, receives no direct beam). A pixel
// count can exceed the patch's projected area by its edge pixels; the fraction is clamped to
// [0, 1] and the clamps are counted (the overshoot guard the scanline codes of urban-climate
// models add afterwards).
//
// The pixel size. A pixel is counted when its centre lies in the projected patch, so the count
// is the area of the patch with each edge moved to the nearest line between pixel centres. In
// the worst case (an edge parallel to the pixel rows, halfway between two of them) that moves an
// edge of length L by h/2 and changes the area by L h / 2; for a projected polygon of perimeter
// P and area A_p,
//     |pixels h² − A_p| ≲ P h / 2,
// and the relative error is at most about P h / A_p (a factor 2 of margin for the corners and
// the rasterizer's snapping of vertices to 1/256 pixel). Asking for the relative error τ on
// every lit patch gives h_i = τ A_p,i / P_i, i.e. K_i = A_p,i / h_i² = P_i² / (τ² A_p,i) pixels
// in patch i (16/τ² for a square, more for slivers); the pixel is the smallest h_i over the lit
// patches. That h is then capped by the pixel budget (SunOptions::max_pixels over the projected
// bounding box) and the result reports the bound it reached, max_i P_i h / A_p,i, and how many
// lit patches exceed τ.
//
// The worst case is far from the typical case: the grid is turned in the plane ⟂ s by φ with
// tan φ = (√5 − 1)/2 (the golden ratio's inverse, the worst-approximable slope), so that the
// edges of axis-aligned buildings never run along the pixel rows (their images lie along the
// horizontal ⟂ s and the image of the vertical, i.e. at φ and φ + 90°). For such an edge the
// counting errors of successive pixel columns do not add up (a discrepancy sum of a badly
// approximable slope): the error per edge grows like h² log(L/h) instead of L h / 2.
//
// Tiles. The grid covers the projected bounding box of the drawn scene, pixel (k, l) centred at
// (u_min + (k + ½) h, v_min + (l + ½) h); it is drawn in square tiles of T pixels (T ≤ the GL's
// texture, renderbuffer and viewport limits), each with the exact sub-range of the same grid, so
// a pixel centre belongs to one tile only. The CPU projects the vertices in double for every
// tile (and leaves out the triangles that miss it); the GL only rasterizes.
//
// Deterministic: the frame, the pixel size and the tiling depend only on the scene, s and the
// options; llvmpipe rasterizes deterministically; the counts are sums of integers.
#include "ffcube/gl/sun.hpp"

#include <fmt/format.h>
#include <glm/geometric.hpp>

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>

#include "ffcube/core/error.hpp"
#include "ffcube/core/timer.hpp"
#include "gl/gl_api.hpp"
#include "gl/objects.hpp"
#include "gl/shaders.hpp"

namespace ffcube {

Vec3 normalized_sun_direction(Vec3 s, const char* option) {
    if (!std::isfinite(s.x) || !std::isfinite(s.y) || !std::isfinite(s.z))
        throw InputError(fmt::format("{} {},{},{}: every component must be a finite number", option, s.x, s.y, s.z));
    const double len = std::sqrt(glm::dot(s, s));
    if (!(len > 0.0) || !std::isfinite(len))
        throw InputError(fmt::format("{} {},{},{}: the direction towards the sun must not be zero", option, s.x, s.y, s.z));
    return s / len;
}

Vec3 sun_direction_from_angles(double azimuth_deg, double elevation_deg) {
    if (!std::isfinite(azimuth_deg) || !std::isfinite(elevation_deg))
        throw InputError(fmt::format("--sun {},{}: azimuth and elevation must be finite numbers (degrees)", azimuth_deg,
                                     elevation_deg));
    if (elevation_deg < -90.0 || elevation_deg > 90.0)
        throw InputError(fmt::format("--sun {},{}: the elevation must be in [-90, 90] degrees", azimuth_deg, elevation_deg));
    const double a = azimuth_deg * std::numbers::pi / 180.0, e = elevation_deg * std::numbers::pi / 180.0;
    // Azimuth clockwise from north (+y) towards east (+x); elevation above the horizon (+z).
    return normalized_sun_direction(Vec3(std::sin(a) * std::cos(e), std::cos(a) * std::cos(e), std::sin(e)), "--sun");
}

namespace {

// n·s at most this: edge-on (a wall under a sun in its own plane, n·s ~ 1e-17 from rounding) or
// facing away; fraction 0. Such a patch would receive at most 1e-9 of its area's beam.
constexpr double kEdgeOn = 1e-9;

struct Frame {
    Vec3 s, e1, e2;
};

// The image axes: the horizontal axis ⟂ s and the image of the vertical (for a sun within ~25°
// of the zenith: the axis ⟂ s and x, and its partner), turned by φ, tan φ = (√5 − 1)/2 (see the top).
Frame make_frame(Vec3 s) {
    const Vec3 ref = std::abs(s.z) < 0.9 ? Vec3(0.0, 0.0, 1.0) : Vec3(0.0, 1.0, 0.0);
    const Vec3 a = glm::normalize(glm::cross(ref, s));
    const Vec3 b = glm::cross(s, a);
    const double t = (std::sqrt(5.0) - 1.0) / 2.0, c = 1.0 / std::sqrt(1.0 + t * t), sn = t * c;
    return {s, c * a + sn * b, -sn * a + c * b};
}

struct Projected {
    double u, v, d;
};

void validate(const SunOptions& o) {
    if (!(o.tolerance > 0.0 && o.tolerance < 1.0))
        throw InputError(fmt::format("sun tolerance {}: must be in (0, 1)", o.tolerance));
    if (o.max_pixels < 1) throw InputError("sun pixel budget: must be at least 1 pixel");
    if (o.tile < 0 || o.tile == 1) throw InputError(fmt::format("sun tile size {}: must be 0 (automatic) or at least 2", o.tile));
}

double pixels_of(double w, double h, double pixel) {
    return std::max(1.0, std::ceil(w / pixel)) * std::max(1.0, std::ceil(h / pixel));
}

}  // namespace

SunResult sunlit_fractions(const Scene& scene, Vec3 towards_sun, const SunOptions& opt) {
    return sunlit_fractions(scene, towards_sun, opt, nullptr);
}

SunResult sunlit_fractions(const Scene& scene, Vec3 towards_sun, const SunOptions& opt, GlContext& context) {
    return sunlit_fractions(scene, towards_sun, opt, &context);
}

SunResult sunlit_fractions(const Scene& scene, Vec3 towards_sun, const SunOptions& opt, GlContext* context) {
    Stopwatch watch;
    validate(opt);
    SunResult r;
    r.sun = normalized_sun_direction(towards_sun);
    const Frame f = make_frame(r.sun);
    const Scene& drawn = scene.drawn_scene();
    const std::size_t n = scene.size();
    r.fraction.assign(n, 0.0);
    r.cosine.assign(n, 0.0);
    r.pixels.assign(n, 0);

    std::vector<Projected> q(drawn.positions.size());
    for (std::size_t i = 0; i < q.size(); ++i) {
        const Vec3& p = drawn.positions[i];
        q[i] = {glm::dot(p, f.e1), glm::dot(p, f.e2), glm::dot(p, f.s)};
    }
    double u_min = std::numeric_limits<double>::infinity(), u_max = -u_min, v_min = u_min, v_max = -u_min,
           d_min = u_min, d_max = -u_min;
    for (const Patch& p : drawn.patches)
        for (std::uint32_t k = 0; k < p.count; ++k) {
            const Projected& c = q[p.v[k]];
            u_min = std::min(u_min, c.u), u_max = std::max(u_max, c.u);
            v_min = std::min(v_min, c.v), v_max = std::max(v_max, c.v);
            d_min = std::min(d_min, c.d), d_max = std::max(d_max, c.d);
        }

    // Per lit patch: its projected area and perimeter, and the pixel they ask for.
    std::vector<double> projected_area(n, 0.0), perimeter(n, 0.0);
    double wanted = std::numeric_limits<double>::infinity();
    for (std::size_t i = 0; i < n; ++i) {
        const Patch& p = scene.patches[i];
        r.cosine[i] = glm::dot(p.normal, r.sun);
        if (!(r.cosine[i] > kEdgeOn)) continue;
        ++r.lit_patches;
        projected_area[i] = p.area * r.cosine[i];
        for (std::uint32_t k = 0; k < p.count; ++k) {
            const Projected &a = q[p.v[k]], &b = q[p.v[(k + 1) % p.count]];
            perimeter[i] += std::hypot(b.u - a.u, b.v - a.v);
        }
        if (perimeter[i] > 0.0 && projected_area[i] > 0.0)
            wanted = std::min(wanted, opt.tolerance * projected_area[i] / perimeter[i]);
    }
    if (r.lit_patches == 0 || !std::isfinite(wanted) || !(wanted > 0.0)) {
        r.seconds = watch.seconds();
        return r;  // nothing faces the sun: every fraction is 0, nothing to draw
    }

    // The pixel: what the tolerance asks, or larger to fit the budget over the projected box.
    const double width = u_max - u_min, height = v_max - v_min;
    const double budget = static_cast<double>(opt.max_pixels);
    double h = wanted;
    r.wanted_pixel_size = wanted;
    if (pixels_of(width, height, h) > budget) {
        h = std::max({std::sqrt(width * height / budget), width / budget, height / budget, wanted});
        while (pixels_of(width, height, h) > budget) h *= 1.0001;
    }
    r.pixel_size = h;
    r.pixels_u = static_cast<std::uint64_t>(std::max(1.0, std::ceil(width / h)));
    r.pixels_v = static_cast<std::uint64_t>(std::max(1.0, std::ceil(height / h)));

    // Triangles of the drawn scene: (corner, corner, corner, ID).
    struct Tri {
        std::uint32_t a, b, c, id;
    };
    std::vector<Tri> tris;
    tris.reserve(drawn.patches.size() * 2);
    for (std::size_t i = 0; i < drawn.patches.size(); ++i) {
        const Patch& p = drawn.patches[i];
        const auto id = static_cast<std::uint32_t>(i + 1);
        tris.push_back({p.v[0], p.v[1], p.v[2], id});
        if (p.count == 4) tris.push_back({p.v[0], p.v[2], p.v[3], id});
    }

    std::vector<std::uint64_t> counts(drawn.patches.size() + 1, 0);
    {
        std::unique_ptr<GlContext> own;  // made here unless the caller lends one
        if (!context) own = create_headless_context(opt.backend);
        GlContext* ctx = context ? context : own.get();
        ctx->make_current();
        r.renderer = ctx->renderer();
        const gl::Api& gl = ctx->api();
        Stopwatch stage;
        {
            GLint tex = 0, rb = 0, vp[2] = {0, 0};
            gl.GetIntegerv(GL_MAX_TEXTURE_SIZE, &tex);
            gl.GetIntegerv(GL_MAX_RENDERBUFFER_SIZE, &rb);
            gl.GetIntegerv(GL_MAX_VIEWPORT_DIMS, vp);
            const int limit = std::min({tex, rb, vp[0], vp[1]});
            if (limit < 2) throw GlError(fmt::format("GL limits too small for the sun item buffer ({})", limit));
            r.tile_size = std::min(opt.tile > 0 ? opt.tile : 4096, limit);
            const auto T = static_cast<std::uint64_t>(r.tile_size);
            r.tiles_u = static_cast<int>((r.pixels_u + T - 1) / T);
            r.tiles_v = static_cast<int>((r.pixels_v + T - 1) / T);
            // The tile need be no larger than the grid.
            r.tile_size = static_cast<int>(std::min<std::uint64_t>(T, std::max(r.pixels_u, r.pixels_v)));

            gl::Program program = gl::make_program(gl, "sun item shader", shaders::sun_vert, shaders::sun_frag);
            gl::ItemTarget target = gl::make_item_target(gl, r.tile_size, r.tile_size);
            gl::VertexArray vao = gl::make_vertex_array(gl);
            gl::Buffer pos_vbo = gl::make_buffer(gl), id_vbo = gl::make_buffer(gl);
            gl.BindVertexArray(vao.id());
            gl.BindBuffer(GL_ARRAY_BUFFER, pos_vbo.id());
            gl.EnableVertexAttribArray(0);
            gl.VertexAttribPointer(0, 3, GL_FLOAT, GL_FALSE, 3 * sizeof(float), nullptr);
            gl.BindBuffer(GL_ARRAY_BUFFER, id_vbo.id());
            gl.EnableVertexAttribArray(1);
            gl.VertexAttribIPointer(1, 1, GL_UNSIGNED_INT, sizeof(std::uint32_t), nullptr);
            gl.UseProgram(program.id());
            gl.BindFramebuffer(GL_FRAMEBUFFER, target.fbo.id());
            gl.Enable(GL_DEPTH_TEST);
            gl.DepthFunc(GL_GREATER);  // larger depth: nearer the sun
            gl.DepthMask(GL_TRUE);
            gl.Disable(GL_CULL_FACE);  // back faces block
            gl.Disable(GL_BLEND);
            gl.Disable(GL_DITHER);
            gl.Disable(GL_MULTISAMPLE);
            gl.Disable(GL_SCISSOR_TEST);
            gl.PixelStorei(GL_PACK_ALIGNMENT, 4);
            gl::check_gl(gl, "sun item buffer setup");
            r.seconds_setup = stage.seconds();

            const double depth_span = d_max - d_min;
            std::vector<float> xyz;
            std::vector<std::uint32_t> ids;
            std::vector<std::uint32_t> image(static_cast<std::size_t>(r.tile_size) * r.tile_size);
            for (int tv = 0; tv < r.tiles_v; ++tv) {
                for (int tu = 0; tu < r.tiles_u; ++tu) {
                    const std::uint64_t k0 = static_cast<std::uint64_t>(tu) * T, l0 = static_cast<std::uint64_t>(tv) * T;
                    const int tw = static_cast<int>(std::min<std::uint64_t>(T, r.pixels_u - k0));
                    const int th = static_cast<int>(std::min<std::uint64_t>(T, r.pixels_v - l0));
                    const double u0 = u_min + static_cast<double>(k0) * h, v0 = v_min + static_cast<double>(l0) * h;
                    const double u1 = u0 + tw * h, v1 = v0 + th * h;
                    stage.restart();
                    xyz.clear();
                    ids.clear();
                    for (const Tri& t : tris) {
                        const Projected &a = q[t.a], &b = q[t.b], &c = q[t.c];
                        // Triangles that miss the tile (by more than a pixel: no centre of it) are left out.
                        if (std::max({a.u, b.u, c.u}) < u0 - h || std::min({a.u, b.u, c.u}) > u1 + h ||
                            std::max({a.v, b.v, c.v}) < v0 - h || std::min({a.v, b.v, c.v}) > v1 + h)
                            continue;
                        for (const Projected* p : {&a, &b, &c}) {
                            xyz.push_back(static_cast<float>(2.0 * (p->u - u0) / (tw * h) - 1.0));
                            xyz.push_back(static_cast<float>(2.0 * (p->v - v0) / (th * h) - 1.0));
                            // Depth in [−0.9, 0.9] (window 0.05 … 0.95): the clear value 0 is behind all.
                            xyz.push_back(static_cast<float>(depth_span > 0.0 ? 1.8 * (p->d - d_min) / depth_span - 0.9 : 0.0));
                            ids.push_back(t.id);
                        }
                    }
                    if (ids.empty()) {
                        r.seconds_project += stage.seconds();
                        continue;
                    }
                    gl.BindBuffer(GL_ARRAY_BUFFER, pos_vbo.id());
                    gl.BufferData(GL_ARRAY_BUFFER, static_cast<GLsizeiptr>(xyz.size() * sizeof(float)), xyz.data(),
                                  GL_STREAM_DRAW);
                    gl.BindBuffer(GL_ARRAY_BUFFER, id_vbo.id());
                    gl.BufferData(GL_ARRAY_BUFFER, static_cast<GLsizeiptr>(ids.size() * sizeof(std::uint32_t)), ids.data(),
                                  GL_STREAM_DRAW);
                    r.seconds_project += stage.seconds();
                    stage.restart();
                    gl.Viewport(0, 0, tw, th);
                    const GLuint zero_id[4] = {0, 0, 0, 0};
                    const GLfloat zero_depth = 0.0f;
                    gl.ClearBufferuiv(GL_COLOR, 0, zero_id);
                    gl.ClearBufferfv(GL_DEPTH, 0, &zero_depth);
                    gl.DrawArrays(GL_TRIANGLES, 0, static_cast<GLsizei>(ids.size()));
                    gl.Finish();
                    r.seconds_draw += stage.seconds();
                    stage.restart();
                    gl.ReadPixels(0, 0, tw, th, GL_RED_INTEGER, GL_UNSIGNED_INT, image.data());
                    gl::check_gl(gl, "sun item buffer tile");
                    r.seconds_readback += stage.seconds();
                    stage.restart();
                    const std::size_t shown = static_cast<std::size_t>(tw) * th;
                    for (std::size_t k = 0; k < shown; ++k) {
                        const std::uint32_t id = image[k];
                        if (id < counts.size()) ++counts[id];
                    }
                    r.seconds_count += stage.seconds();
                }
            }
            gl.BindVertexArray(0);
            gl.BindFramebuffer(GL_FRAMEBUFFER, 0);
        }  // GL objects deleted while the context is current
        ctx->release_current();
    }

    const double pixel_area = h * h;
    for (std::size_t i = 0; i < n; ++i) {
        r.pixels[i] = counts[i + 1];
        if (!(r.cosine[i] > kEdgeOn)) continue;
        double share = projected_area[i] > 0.0 ? static_cast<double>(r.pixels[i]) * pixel_area / projected_area[i] : 0.0;
        if (share > 1.0) {
            ++r.clamped;
            r.max_overshoot = std::max(r.max_overshoot, share - 1.0);
            share = 1.0;
        }
        r.fraction[i] = share;
        r.sunlit_projected_area += share * projected_area[i];
        const double bound = projected_area[i] > 0.0 ? perimeter[i] * h / projected_area[i] : 0.0;
        r.error_bound = std::max(r.error_bound, bound);
        if (bound > opt.tolerance) ++r.under_resolved;
    }
    r.seconds = watch.seconds();
    return r;
}

}  // namespace ffcube
