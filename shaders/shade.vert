#version 450 core
// Pictures of the solved scene: positions arrive relative to the eye (subtracted in double on the
// CPU, so large coordinates keep their precision), with the value to show at each vertex.
layout(location = 0) in vec3 a_position;
layout(location = 1) in vec3 a_value;
uniform mat4 u_view_projection;
out vec3 v_smooth;
flat out vec3 v_flat;  // the provoking (last) vertex's value; a flat-shaded face has one value
void main() {
    v_smooth = a_value;
    v_flat = a_value;
    gl_Position = u_view_projection * vec4(a_position, 1.0);
}
