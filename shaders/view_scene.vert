#version 450 core
// ffcube view: one vertex per patch corner (see viewer/display.hpp). The colour is the patch's
// (flat shading) or the corner's smoothed radiosity, or a heat-map colour; the patch index goes to
// the ID pass for picking.
layout(location = 0) in vec3 a_position;
layout(location = 1) in vec3 a_color;
layout(location = 2) in uint a_patch;

uniform mat4 u_view_proj;

out vec3 v_color;
flat out uint v_patch;

void main() {
    v_color = a_color;
    v_patch = a_patch;
    gl_Position = u_view_proj * vec4(a_position, 1.0);
}
