#version 450 core
// Front faces show their (interpolated or flat) value; faces are one-sided, so a back face shows
// the caller's neutral value. Alpha 1 marks geometry (the clear value is 0).
in vec3 v_smooth;
flat in vec3 v_flat;
uniform int u_flat;
uniform vec3 u_back;
layout(location = 0) out vec4 o_color;
void main() {
    if (!gl_FrontFacing)
        o_color = vec4(u_back, 1.0);
    else
        o_color = vec4(u_flat != 0 ? v_flat : v_smooth, 1.0);
}
