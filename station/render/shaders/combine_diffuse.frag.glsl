#version 430
// Pre-mix the diffuse base of both paints under a clear coat into one atlas (the atlas layout of
// atlas.glsl, faces of u_size texels): render.frag.glsl's base terms
//   base_p(N) = wd_p D(N) + wk_p (D_coat(N) - D(N)) = u_w_plain[p] D(N) + u_w_coat[p] D_coat(N)
// (u_w_plain = wd - wk = pi K_A, u_w_coat = wk = pi K_D; station.model.gloss.ClearCoat), linear in the maps, so a paint pixel
// reads its base in one lookup instead of two. Texel centres and borders as in combine.frag.glsl: a border
// texel holds the neighbouring face's edge texel. Rebuilt only when the weights or the coat change.
//#include cubeface.glsl
uniform samplerCube u_diffuse, u_diffuse_coat;
uniform vec3 u_w_plain[2], u_w_coat[2];
uniform int u_size;
out vec4 f_color;

void main() {
    ivec2 p = ivec2(gl_FragCoord.xy);
    int tile = u_size + 2;
    int block = p.y / tile;  // paint * 6 + face
    int paint = block / 6;
    int face = block - 6 * paint;
    int row = p.y - block * tile;
    float a = (2.0 * float(p.x) - 1.0) / float(u_size) - 1.0;
    float b = (2.0 * float(row) - 1.0) / float(u_size) - 1.0;
    vec3 r = cube_face_dir(face, a, b);
    vec2 ab;
    int f2 = cube_face_of(r, ab);
    vec2 cell = clamp(floor((ab + 1.0) * (0.5 * float(u_size))), 0.0, float(u_size - 1));
    ab = (2.0 * cell + 1.0) / float(u_size) - 1.0;
    r = cube_face_dir(f2, ab.x, ab.y);
    vec3 base = u_w_plain[paint] * textureLod(u_diffuse, r, 0.0).rgb
              + u_w_coat[paint] * textureLod(u_diffuse_coat, r, 0.0).rgb;
    f_color = vec4(base, 1.0);
}
