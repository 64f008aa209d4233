#version 450 core
// Item-buffer vertex shader. Positions arrive already relative to the hemicube eye and in the
// hemicube's local frame (subtracted in double on the CPU), so only the fixed face projection
// is applied here.
layout(location = 0) in vec3 a_position;
uniform mat4 u_face;  // projection × view of one hemicube face (reversed-Z, infinite far plane)
void main() { gl_Position = u_face * vec4(a_position, 1.0); }
