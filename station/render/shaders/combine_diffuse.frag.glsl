#version 430
// Pre-mix the diffuse base of both paints under a clear coat into one atlas (the atlas layout of
// atlas.glsl, faces of u_size texels): render.frag.glsl's base terms
//   base_p(N) = wd_p D(N) + wk_p (D_coat(N) - D(N)) = u_w_plain[p] D(N) + u_w_coat[p] D_coat(N)
// (u_w_plain = wd - wk = pi K_A, u_w_coat = wk = pi K_D; station.model.gloss.ClearCoat), linear in the
// maps, so a paint pixel reads its base in one lookup instead of two. Texel centres and borders:
// atlas_texel_direction (cubeface.glsl). Rebuilt only when the weights or the coat change.
//#include cubeface.glsl
uniform samplerCube u_diffuse, u_diffuse_coat;
uniform vec3 u_w_plain[2], u_w_coat[2];
uniform int u_size;
out vec4 f_color;

void main() {
    int paint;
    vec3 r = atlas_texel_direction(ivec2(gl_FragCoord.xy), u_size, paint);
    vec3 base = u_w_plain[paint] * textureLod(u_diffuse, r, 0.0).rgb
              + u_w_coat[paint] * textureLod(u_diffuse_coat, r, 0.0).rgb;
    f_color = vec4(base, 1.0);
}
