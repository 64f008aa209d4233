#version 450 core
// ffcube view: patch outlines (the wireframe overlay and the picked patch), one colour; also the
// translucent fill of obstruction-only surfaces (u_alpha < 1, blended).
uniform vec3 u_color;
uniform float u_alpha = 1.0;

layout(location = 0) out vec4 frag_color;

void main() {
    frag_color = vec4(u_color, u_alpha);
}
