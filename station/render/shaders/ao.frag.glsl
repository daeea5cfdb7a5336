#version 430
// Ambient occlusion of the ground by a mesh (station/render/gl_shadows.py, module docstring): the mesh as
// columns between its bottom and top heights (u_bottom, u_top: depth maps from below and above over the
// box [u_box_lo, u_box_hi] in x, z); per texel p of the ground disc's square the cosine-weighted occluded
// fraction O = mean over AO_AZIMUTHS azimuths of sin^2 phi_max - sin^2 phi_min, the elevations the
// columns met along the azimuth span (AO_STEPS columns across the box).
uniform sampler2D u_top, u_bottom;
uniform vec2 u_box_lo, u_box_hi;
uniform mat4 u_top_mat;  // world -> (u, v) of both height maps
uniform vec4 u_heights;  // (lo, span) from above, (lo, span) from below: y = -(lo + d span), lo + d span
uniform float u_ground_y, u_ground_radius;
uniform vec2 u_ground_c, u_size;
out vec4 f_color;
const float PI = 3.14159265358979;

void main() {
    vec2 q = 2.0 * gl_FragCoord.xy / u_size - 1.0;
    vec2 p = u_ground_c + q * u_ground_radius;  // (x, z) of the ground point
    float occluded = 0.0;
    for (int j = 0; j < AO_AZIMUTHS; ++j) {
        float a = 2.0 * PI * (float(j) + 0.5) / float(AO_AZIMUTHS);
        vec2 dir = vec2(cos(a), sin(a));
        // the ray p + s dir across the box (slab test)
        vec2 inv = 1.0 / (abs(dir) + 1e-9) * sign(dir + 1e-12);
        vec2 t0 = (u_box_lo - p) * inv, t1 = (u_box_hi - p) * inv;
        float s_in = max(max(min(t0.x, t1.x), min(t0.y, t1.y)), 0.0);
        float s_out = min(max(t0.x, t1.x), max(t0.y, t1.y));
        if (s_out <= s_in) continue;
        float lo2 = 1.0, hi2 = 0.0;  // sin^2 of the lowest and highest elevation hidden
        for (int i = 0; i < AO_STEPS; ++i) {
            float s = mix(s_in, s_out, (float(i) + 0.5) / float(AO_STEPS));
            vec2 x = p + s * dir;
            vec2 uv = (u_top_mat * vec4(x.x, 0.0, x.y, 1.0)).xy;
            float top = -(u_heights.x + textureLod(u_top, uv, 0.0).r * u_heights.y) - u_ground_y;
            float bottom = u_heights.z + textureLod(u_bottom, uv, 0.0).r * u_heights.w - u_ground_y;
            if (top > bottom && top > 0.0) {
                float b = max(bottom, 0.0);
                lo2 = min(lo2, b * b / (b * b + s * s));
                hi2 = max(hi2, top * top / (top * top + s * s));
            }
        }
        occluded += max(hi2 - lo2, 0.0);
    }
    f_color = vec4(clamp(occluded / float(AO_AZIMUTHS), 0.0, 1.0), 0.0, 0.0, 1.0);
}
