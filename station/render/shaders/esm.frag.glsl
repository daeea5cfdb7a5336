#version 430
// One pass of the exponential shadow map's box filter in log space (station/render/gl_shadows.py): along
// u_step (uv per tap), ESM_TAPS taps, L = m + log(mean_i exp(c (d_i - m))) / c with m = max_i d_i, so
// exp(c L) is the mean of exp(c d) without overflow. u_src: the light's depth map (first pass) or the
// previous pass's L.
uniform sampler2D u_src;
uniform vec2 u_step, u_size;
uniform float u_c;
out vec4 f_color;

void main() {
    vec2 uv = gl_FragCoord.xy / u_size;
    float d[ESM_TAPS];
    float m = -1e30;
    for (int i = 0; i < ESM_TAPS; ++i) {
        d[i] = textureLod(u_src, uv + (float(i) - 0.5 * float(ESM_TAPS - 1)) * u_step, 0.0).r;
        m = max(m, d[i]);
    }
    float sum = 0.0;
    for (int i = 0; i < ESM_TAPS; ++i) sum += exp(u_c * (d[i] - m));
    f_color = vec4(m + log(sum / float(ESM_TAPS)) / u_c, 0.0, 0.0, 1.0);
}
