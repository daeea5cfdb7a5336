#version 430
// Pre-combine the lobe maps of both paints into two atlases (thesis eqs 2.5.1-2.5.2; the image is linear
// in the weights):
//   gloss_p(R) = sum_i wg_{p,i} C_i(R)      dd_p(R) = sum_i wdd_{p,i} C_i(R)
// so the per-pixel shader needs 2 lookups for either paint instead of one per lobe and paint. Atlas
// layout (atlas.glsl): 12 cube faces of u_size texels plus a 1-texel border each (faces 0..5 of paint 0,
// then of paint 1, stacked in y); a border texel holds the neighbouring face's edge texel, so bilinear
// filtering across a face edge is a seamless cube lookup. Rebuilt only when the weights
// change; the shader that reads it never reads it back to the CPU.
//#include cubeface.glsl
uniform samplerCube u_lobes[N_LOBES];
uniform float u_wg[2 * N_LOBES];
uniform vec3 u_wdd[2 * N_LOBES];
uniform int u_size;
layout(location = 0) out vec4 f_gloss;
layout(location = 1) out vec4 f_dd;

void main() {
    int paint;
    vec3 r = atlas_texel_direction(ivec2(gl_FragCoord.xy), u_size, paint);
    vec3 g = vec3(0.0), dd = vec3(0.0);
    for (int i = 0; i < N_LOBES; ++i) {
        vec3 c = textureLod(u_lobes[i], r, 0.0).rgb;
        g += u_wg[paint * N_LOBES + i] * c;
        dd += u_wdd[paint * N_LOBES + i] * c;
    }
    f_gloss = vec4(g, 1.0);
    f_dd = vec4(dd, 1.0);
}
