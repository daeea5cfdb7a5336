#version 430
// Pre-combine the lobe maps of one paint into two cube maps (faces stacked in an (S, 6S) target):
//   gloss(R) = sum_i wg_i C_i(R)      dd(R) = sum_i wdd_i C_i(R)
// so the per-pixel shader needs 2 lookups per paint instead of one per lobe (the image is linear in
// the weights, thesis eqs 2.5.1-2.5.2). Rebuilt only when the weights change.
//#include cubeface.glsl
uniform samplerCube u_lobes[N_LOBES];
uniform float u_wg[N_LOBES];
uniform vec3 u_wdd[N_LOBES];
uniform int u_size;
layout(location = 0) out vec4 f_gloss;
layout(location = 1) out vec4 f_dd;

void main() {
    ivec2 p = ivec2(gl_FragCoord.xy);
    int face = p.y / u_size;
    int row = p.y - face * u_size;
    float a = 2.0 * (float(p.x) + 0.5) / float(u_size) - 1.0;
    float b = 2.0 * (float(row) + 0.5) / float(u_size) - 1.0;
    vec3 r = cube_face_dir(face, a, b);
    vec3 g = vec3(0.0), dd = vec3(0.0);
    for (int i = 0; i < N_LOBES; ++i) {
        vec3 c = textureLod(u_lobes[i], r, 0.0).rgb;
        g += u_wg[i] * c;
        dd += u_wdd[i] * c;
    }
    f_gloss = vec4(g, 1.0);
    f_dd = vec4(dd, 1.0);
}
