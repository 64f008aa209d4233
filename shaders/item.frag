#version 450 core
// Writes the ID of the visible patch: 1 + patch index for a front face, 0xFFFFFFFF for a back
// face (it blocks but receives nothing); the clear value 0 means nothing was hit.
// The patch of triangle k of this draw is u_ids[u_base + k] (gl_PrimitiveID restarts per draw).
layout(binding = 0) uniform usamplerBuffer u_ids;
uniform int u_base;
layout(location = 0) out uint o_id;
void main() { o_id = gl_FrontFacing ? texelFetch(u_ids, u_base + gl_PrimitiveID).r : 0xFFFFFFFFu; }
