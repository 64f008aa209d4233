#version 450 core
// Item-buffer vertex shader. A whole mesher piece (a quad split into a grid of patches, or a
// triangle split into similar triangles) is drawn at once; the fragment shader finds the patch.
// A vertex's position relative to the hemicube eye in the hemicube's local frame, then the fixed
// face projection. WORLD_POSITIONS 1: the world positions are uploaded once, as doubles, and the
// eye and frame come per hemicube in a uniform block; the subtraction and the three dot products
// are done in double here, `precise` (no fused multiply-add, no reordering), in the order the CPU
// does them for culling (glm::dot: x, y, then z), and rounded once to float: the same bits as the
// CPU's, so what is drawn is what was culled. WORLD_POSITIONS 0: the CPU uploads those floats
// every hemicube.
#ifndef WORLD_POSITIONS
#define WORLD_POSITIONS 0
#endif
#if WORLD_POSITIONS
layout(location = 0) in dvec3 a_world;  // static
layout(std140, binding = 1) uniform HemicubeEye {
    dvec4 u_eye, u_tangent, u_bitangent, u_normal;  // .xyz used
};
vec3 local_position() {
    precise dvec3 d = a_world - u_eye.xyz;
    precise double x = d.x * u_tangent.x + d.y * u_tangent.y + d.z * u_tangent.z;
    precise double y = d.x * u_bitangent.x + d.y * u_bitangent.y + d.z * u_bitangent.z;
    precise double z = d.x * u_normal.x + d.y * u_normal.y + d.z * u_normal.z;
    return vec3(float(x), float(y), float(z));
}
#else
layout(location = 0) in vec3 a_position;  // per hemicube
vec3 local_position() { return a_position; }
#endif
layout(location = 1) in vec2 a_param;     // cell coordinates (affine pieces) or plane coordinates (static)
layout(location = 3) in uvec4 a_info;     // the piece's kind, nu, nv, first patch (static)
uniform mat4 u_face;  // projection × view of one hemicube face (reversed-Z, infinite far plane)
// SINGLE_CELL 1: every piece is one patch (defined by the program that loads this shader, for
// the front pass only): the fragment writes its piece's patch, and nothing else is interpolated.
#ifndef SINGLE_CELL
#define SINGLE_CELL 0
#endif
#if SINGLE_CELL
flat out uint v_id;
void main() {
    v_id = a_info.w + 1u;
    gl_Position = u_face * vec4(local_position(), 1.0);
}
#else
#ifndef HAS_BILINEAR
#define HAS_BILINEAR 1
#endif
out vec2 v_param;
flat out uvec4 v_info;
#if HAS_BILINEAR
// The piece's corners 1..3 in its plane coordinates (see item.frag), per vertex (static), passed
// on flat: a read of a buffer per pixel (a gather in llvmpipe) cost as much as the rest of the
// drawing (docs/benchmarks.md, "The bilinear pieces' corners as flat varyings").
layout(location = 2) in vec2 a_q1;
layout(location = 4) in vec2 a_q2;
layout(location = 5) in vec2 a_q3;
flat out vec2 v_q1, v_q2, v_q3;
#endif
void main() {
    v_param = a_param;
    v_info = a_info;
#if HAS_BILINEAR
    v_q1 = a_q1;
    v_q2 = a_q2;
    v_q3 = a_q3;
#endif
    gl_Position = u_face * vec4(local_position(), 1.0);
}
#endif
