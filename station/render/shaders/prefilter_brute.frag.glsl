#version 430
// Reference prefilter by quadrature over every source texel: the GL twin of
// station.render.prefilter.prefilter_brute (same float32 terms, summed in another order).
// P_n(R) = sum_k L_k s_k (n+1)/(2 pi) max(R.w_k, 1e-30)^n / sum_k s_k (n+1)/(2 pi) max(R.w_k, 1e-30)^n,
// s_k the exact solid angle of source texel k. The output texel directions come from a texture (the
// NumPy ones, so both paths evaluate the same R); the target is (S_out, 6 S_out), faces stacked.
uniform sampler2D u_out_dirs;  // (S_out, 6 S_out): unit direction of each output texel
uniform sampler2D u_src_dirs;  // (S, 6 S): unit direction of each source texel
uniform sampler2D u_src_rad;   // (S, 6 S): radiance x solid angle (rgb), solid angle (a)
uniform float u_exponent;
// Clear coat's entry weight on the radiance terms (prefilter.coat_diffuse_map, ClearCoat.entry_scale):
// (1 - F(R.w; u_coat_n)) / u_coat_t, u_coat_t = 1 - F_dr,ext; u_coat_n = 0: none.
uniform float u_coat_n;
uniform float u_coat_t;
out vec4 f_color;

//#include coat.glsl

float entry(float c) {
    return u_coat_n <= 0.0 ? 1.0 : coat_entry_weight(c, u_coat_n, u_coat_t);
}

void main() {
    vec3 R = texelFetch(u_out_dirs, ivec2(gl_FragCoord.xy), 0).xyz;
    ivec2 n = textureSize(u_src_dirs, 0);
    float k = (u_exponent + 1.0) / (2.0 * 3.14159265358979);
    vec4 acc = vec4(0.0);
    for (int y = 0; y < n.y; ++y) {
        for (int x = 0; x < n.x; ++x) {
            float d = dot(R, texelFetch(u_src_dirs, ivec2(x, y), 0).xyz);
            float c = max(d, 1e-30);
            vec4 rad = texelFetch(u_src_rad, ivec2(x, y), 0);
            acc += (k * exp(u_exponent * log(c))) * vec4(entry(d) * rad.rgb, rad.a);
        }
    }
    f_color = vec4(acc.rgb / acc.a, 1.0);
}
