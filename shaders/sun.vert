#version 450 core
// Sun item buffer (src/gl/sun_buffer.cpp): one vertex per patch corner, already projected by the
// CPU (in double) onto the tile's orthographic frame; the patch's ID passes flat.
layout(location = 0) in vec3 a_ndc;
layout(location = 1) in uint a_id;  // 1 + patch index
flat out uint v_id;
void main() {
    v_id = a_id;
    gl_Position = vec4(a_ndc, 1.0);
}
