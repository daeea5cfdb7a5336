// Lookup in a cube-face atlas (shaders/combine.frag.glsl, combine_diffuse.frag.glsl): faces 0..5 = +X -X
// +Y -Y +Z -Z of each of two paints, `face` texels plus a 1-texel border per face, stacked in y. The face
// and its (a, b) come from cube_face_of (OpenGL 4.5 table 8.19); the border makes the bilinear filter
// seamless. atlas_uv: the narrow lobes' atlases (ATLAS_FACE texels a face).
//#include cubeface.glsl
vec2 atlas_uv_of(vec3 d, int paint, int face_texels) {
    vec2 ab;
    int face = cube_face_of(d, ab);
    float tile = float(face_texels + 2);
    vec2 t = (ab + 1.0) * (0.5 * float(face_texels)) + 1.0;  // texels from the tile's corner
    return vec2(t.x / tile, (float(paint * 6 + face) * tile + t.y) / (12.0 * tile));
}

vec2 atlas_uv(vec3 d, int paint) {
    return atlas_uv_of(d, paint, ATLAS_FACE);
}
