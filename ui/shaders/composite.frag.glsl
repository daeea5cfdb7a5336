#version 330
// Re-weighting of cached basis images (thesis eqs 2.5.1-2.5.3, same equation as
// station/render/numpy_renderer.py and ui/models/view.py BasisImages.composite_linear):
//   radiance = wd * D(N) + sum_i (wg_i + (N.V) wdd_i) * C_i(R)
// u_basis is an atlas of layers stacked in y, u_size texels each (RGB9_E5 shared-exponent HDR, 4 bytes
// a texel: llvmpipe is bandwidth-bound): layer 0 is D(N), layer i + 1 is C_i(R). u_geom = (N.V, paint
// id), paint -1 off the object. Weights are LobeWeights.map_weights() of paint 0 and paint 1, compacted
// to the N_ACTIVE lobes with a non-zero weight in either paint (zero terms skipped: same sum, fewer
// fetches); every array index is uniform across pixels. Display transform: the formulas of
// station/render/tonemap.py (exposure, ACES fit, exact sRGB OETF).
uniform sampler2D u_basis;
uniform sampler2D u_geom;
uniform vec2 u_viewport;
uniform ivec2 u_size;
uniform vec3 u_wd0, u_wd1;
uniform int u_n_active;
uniform int u_layer[MAX_LOBES];
uniform vec3 u_wdd0[MAX_LOBES], u_wdd1[MAX_LOBES];
uniform vec2 u_wg[MAX_LOBES];   // (paint 0, paint 1)
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
        rgb = (right ? u_wd1 : u_wd0) * texelFetch(u_basis, px, 0).rgb;
        for (int j = 0; j < u_n_active; ++j) {
            vec3 w = (right ? u_wg[j].y : u_wg[j].x) + geom.r * (right ? u_wdd1[j] : u_wdd0[j]);
            rgb += w * texelFetch(u_basis, px + ivec2(0, u_layer[j] * u_size.y), 0).rgb;
        }
    }
    f_color = vec4(srgb_encode(tone_curve(rgb * u_exposure)), 1.0);
}
