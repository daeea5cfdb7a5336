// Lookup in a cube-face atlas (shaders/combine.frag.glsl): faces 0..5 = +X -X +Y -Y +Z -Z of each of two
// paints, ATLAS_FACE texels plus a 1-texel border per face, stacked in y. The face and its (a, b) come
// from cube_face_of (OpenGL 4.5 table 8.19); the border makes the bilinear filter seamless.
//#include cubeface.glsl
vec2 atlas_uv(vec3 d, int paint) {
    vec2 ab;
    int face = cube_face_of(d, ab);
    const float tile = float(ATLAS_FACE + 2);
    vec2 t = (ab + 1.0) * (0.5 * float(ATLAS_FACE)) + 1.0;  // texels from the tile's corner
    return vec2(t.x / tile, (float(paint * 6 + face) * tile + t.y) / (12.0 * tile));
}
