#version 450 core
// HAS_TRIANGLES, HAS_BILINEAR: 0 when no piece of the scene is a triangle / a quad that is not a
// parallelogram (defined by the program that loads this shader; llvmpipe pays for dead paths).
#ifndef HAS_TRIANGLES
#define HAS_TRIANGLES 1
#endif
#ifndef HAS_BILINEAR
#define HAS_BILINEAR 1
#endif
// BACK_PASS 1: the program of the back-face pass (only writes 0xFFFFFFFF, see below).
#ifndef BACK_PASS
#define BACK_PASS 0
#endif
// Writes the ID of the visible patch: 1 + patch index for a front face, 0xFFFFFFFF for a back
// face (it blocks but receives nothing); the clear value 0 means nothing was hit. Front or back
// is the draw pass's (BACK_PASS: the CPU's classification of the whole piece), not gl_FrontFacing,
// which a sliver snapped to the subpixel grid can get wrong.
// The patch comes from the fragment's position in its piece (perspective-correct, so exact up to
// float rounding): for affine pieces (triangles; quads that are parallelograms, kind 5) the vertex
// parameter is already the cell coordinate, and the patch is its floor; other quads carry plane
// coordinates and need the inverse bilinear map.
#ifndef SINGLE_CELL
#define SINGLE_CELL 0
#endif
// ONLY_KIND 3, 4 or 5: the front pass draws each kind of piece with its own program, which
// computes only that kind's patch lookup (0: every kind present, chosen per piece).
#ifndef ONLY_KIND
#define ONLY_KIND 0
#endif
#if SINGLE_CELL && !BACK_PASS
flat in uint v_id;
layout(location = 0) out uint o_id;
#else
in vec2 v_param;
flat in uvec4 v_info;  // kind (3, 4 or 5), nu, nv, first patch
#if HAS_BILINEAR
flat in vec2 v_q1, v_q2, v_q3;  // corners 1..3 in the piece's plane coordinates (corner 0 at the origin)
#endif
layout(location = 0) out uint o_id;

float cross2(vec2 a, vec2 b) { return a.x * b.y - a.y * b.x; }

#if HAS_BILINEAR
// Quad kind 4: (u, v) ∈ [0, 1]² of plane point h (inverse bilinear).
vec2 inverse_bilinear(vec2 h) {
    // p = u(1-v) q1 + uv q2 + (1-u)v q3: solve k2 v² + k1 v + k0 = 0 (Quilez's inverse
    // bilinear), with the cancellation-free root for near-parallelograms (k2 → 0).
    vec2 e = v_q1, f = v_q3, gg = v_q2 - v_q1 - v_q3;
    float k2 = cross2(gg, f), k1 = cross2(e, f) + cross2(h, gg), k0 = cross2(h, e);
    float disc = sqrt(max(k1 * k1 - 4.0 * k0 * k2, 0.0));
    float q = -0.5 * (k1 + (k1 >= 0.0 ? disc : -disc));
    float v = q != 0.0 ? k0 / q : 0.0;
    if ((v < -0.01 || v > 1.01) && k2 != 0.0) v = q / k2;
    vec2 den = e + gg * v;
    float u = abs(den.x) > abs(den.y) ? (h.x - f.x * v) / den.x : (h.y - f.y * v) / den.y;
    return vec2(u, v);
}
#else
vec2 inverse_bilinear(vec2 h) { return vec2(0.0); }  // no piece of the scene needs it
#endif
#endif

#if BACK_PASS
// How far the pixel centre lies outside its piece, in parts of the piece (≤ 0: inside).
float outside() {
    uint kind = v_info.x;
    vec2 p = v_param;
    if (kind == 3u) return max(max(-p.x, -p.y), p.x + p.y - float(v_info.y)) / float(v_info.y);
    vec2 uv = kind == 5u ? p / vec2(v_info.yz) : inverse_bilinear(p);
    return max(max(-uv.x, -uv.y), max(uv.x, uv.y) - 1.0);
}

// A back face blocks only where its pixel centre lies in it. The rasterizer snaps vertices to
// 1/256 pixel, so at a silhouette (a front piece folding into a back piece behind it: inside a
// torus, over a terrain's ridge) it covers pixel centres up to ~1/360 pixel beyond the shared
// edge with both pieces, and there the back piece's plane, extrapolated, is nearer than the
// front's: closed meshes lost such pixels to back faces (tests/scene/corpus). A centre beyond
// the edge by more than kOutside of the piece is left to what lies behind (the front piece at a
// silhouette). kOutside is far above the interpolated parameters' float rounding (~1e-7 of the
// piece), so where two back pieces share an edge no crack opens between them.
const float kOutside = 4e-6;
void main() {
    if (outside() > kOutside) discard;
    o_id = 0xFFFFFFFFu;
}
#elif SINGLE_CELL
// Every piece is one patch (SINGLE_CELL, item.vert): the vertex shader passes 1 + its patch.
void main() { o_id = v_id; }
#else
void main() {
    uint kind = v_info.x, nu = v_info.y, nv = v_info.z;
    vec2 p = v_param;
    uint cell;
    if (ONLY_KIND == 3 || (ONLY_KIND == 0 && HAS_TRIANGLES != 0 && kind == 3u)) {
        // p = (s, t): k × the barycentric coordinates of corners 1 and 2.
        float k = float(nu);
        float s = clamp(p.x, 0.0, k), t = clamp(p.y, 0.0, k);
        int i = min(int(s), int(nu) - 1), j = min(int(t), int(nu) - 1);
        if (i + j > int(nu) - 1) i = int(nu) - 1 - j;  // rounding past the hypotenuse
        bool inverted = (s - float(i)) + (t - float(j)) > 1.0 && i + j + 1 < int(nu);
        cell = uint(j * (2 * int(nu) - j) + 2 * i + (inverted ? 1 : 0));
    } else if (ONLY_KIND == 5 || (ONLY_KIND == 0 && (HAS_BILINEAR == 0 || kind == 5u))) {
        // p = (u nu, v nv).
        int i = clamp(int(floor(p.x)), 0, int(nu) - 1);
        int j = clamp(int(floor(p.y)), 0, int(nv) - 1);
        cell = uint(j) * nu + uint(i);
    } else {
        vec2 uv = inverse_bilinear(p);
        float u = uv.x, v = uv.y;
        int i = clamp(int(floor(u * float(nu))), 0, int(nu) - 1);
        int j = clamp(int(floor(v * float(nv))), 0, int(nv) - 1);
        cell = uint(j) * nu + uint(i);
    }
    o_id = v_info.w + cell + 1u;
}
#endif
