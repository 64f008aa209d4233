#version 450 core
// ffcube view: from radiosity to the screen.
//   u_mode 0: radiosity × 2^exposure, tone mapped (u_tone_map 0 clamp, 1 Reinhard, 2 ACES
//             filmic fit), then sRGB-encoded by hand (the window's framebuffer is not sRGB);
//   u_mode 1: the colour as it is: heat-map colours (already display values), or linear
//             radiosity into an RGBA32F target for the EXR.
in vec3 v_color;

uniform int u_mode;
uniform float u_exposure;
uniform int u_tone_map;

layout(location = 0) out vec4 frag_color;

vec3 tone_map(vec3 x) {
    if (u_tone_map == 1) return x / (1.0 + x);
    if (u_tone_map == 2) {
        // Narkowicz's fit of the ACES filmic curve.
        return clamp((x * (2.51 * x + 0.03)) / (x * (2.43 * x + 0.59) + 0.14), 0.0, 1.0);
    }
    return clamp(x, 0.0, 1.0);
}

vec3 srgb_encode(vec3 c) {
    return mix(12.92 * c, 1.055 * pow(c, vec3(1.0 / 2.4)) - 0.055, step(vec3(0.0031308), c));
}

void main() {
    if (u_mode == 1) {
        frag_color = vec4(v_color, 1.0);
    } else {
        frag_color = vec4(srgb_encode(tone_map(max(v_color, vec3(0.0)) * exp2(u_exposure))), 1.0);
    }
}
