#version 330
// Re-weighting of cached basis images (thesis eqs 2.5.1-2.5.3; station/render/basis_images.py):
//   rgb = sum_j (a_j + c * b_j) * I_j,   c = N.V,
// where I_j are the core's cached images (diffuse map, horizon-weighted lobe lookups, narrow-lobe
// lookups) and (a_j, b_j) the paint's weights for image j (ui/models/view.py layer_weights).
// u_basis is an atlas of the images stacked in y, u_size texels each (RGB9_E5 shared-exponent HDR,
// 4 bytes a texel: llvmpipe is bandwidth-bound). u_geom = (N.V, paint id), paint -1 off the object.
// Only images with a non-zero weight in either paint are listed (N_ACTIVE; same sum, fewer fetches);
// every array index is uniform across pixels. Display transform: station/render/tonemap.py's formulas
// (exposure, ACES fit, exact sRGB OETF).
uniform sampler2D u_basis;
uniform sampler2D u_geom;
uniform vec2 u_viewport;
uniform ivec2 u_size;
uniform int u_n_active;
uniform int u_layer[MAX_LAYERS];
uniform vec3 u_a0[MAX_LAYERS], u_b0[MAX_LAYERS], u_a1[MAX_LAYERS], u_b1[MAX_LAYERS];
uniform float u_exposure;       // 2^EV
uniform vec3 u_background;
out vec4 f_color;

vec3 tone_curve(vec3 x) {
    x = max(x, vec3(0.0));
    return clamp(x * (2.51 * x + 0.03) / (x * (2.43 * x + 0.59) + 0.14), 0.0, 1.0);
}

vec3 srgb_encode(vec3 x) {
    x = clamp(x, 0.0, 1.0);
    return mix(1.055 * pow(x, vec3(1.0 / 2.4)) - 0.055, 12.92 * x, lessThanEqual(x, vec3(0.0031308)));
}

void main() {
    // Image row 0 is the top row: flip y.
    ivec2 px = ivec2(gl_FragCoord.x * float(u_size.x) / u_viewport.x,
                     float(u_size.y) - gl_FragCoord.y * float(u_size.y) / u_viewport.y);
    px = clamp(px, ivec2(0), u_size - 1);
    vec2 geom = texelFetch(u_geom, px, 0).rg;
    vec3 rgb = u_background;
    if (geom.g > -0.5) {
        bool right = geom.g > 0.5;
        rgb = vec3(0.0);
        for (int j = 0; j < u_n_active; ++j) {
            vec3 w = right ? u_a1[j] + geom.r * u_b1[j] : u_a0[j] + geom.r * u_b0[j];
            rgb += w * texelFetch(u_basis, px + ivec2(0, u_layer[j] * u_size.y), 0).rgb;
        }
    }
    f_color = vec4(srgb_encode(tone_curve(rgb * u_exposure)), 1.0);
}
