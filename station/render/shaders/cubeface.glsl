// Direction of cube-face coordinates (a, b) in [-1, 1] for face 0..5 = +X -X +Y -Y +Z -Z
// (OpenGL 4.5 table 8.19; the same convention as station.render.cubemap.face_directions).
vec3 cube_face_dir(int face, float a, float b) {
    if (face == 0) return vec3(1.0, -b, -a);
    if (face == 1) return vec3(-1.0, -b, a);
    if (face == 2) return vec3(a, 1.0, b);
    if (face == 3) return vec3(a, -1.0, -b);
    if (face == 4) return vec3(a, -b, 1.0);
    return vec3(-a, -b, -1.0);
}

// Inverse of cube_face_dir: the face a direction d (any length) points into and its (a, b) there.
int cube_face_of(vec3 d, out vec2 ab) {
    vec3 q = abs(d);
    if (q.x >= q.y && q.x >= q.z) {
        ab = vec2(d.x > 0.0 ? -d.z : d.z, -d.y) / q.x;
        return d.x > 0.0 ? 0 : 1;
    }
    if (q.y >= q.z) {
        ab = vec2(d.x, d.y > 0.0 ? d.z : -d.z) / q.y;
        return d.y > 0.0 ? 2 : 3;
    }
    ab = vec2(d.z > 0.0 ? d.x : -d.x, -d.y) / q.z;
    return d.z > 0.0 ? 4 : 5;
}

// The direction an atlas texel p holds (atlas.glsl's layout: 12 tiles of face_texels + 2 texels stacked in
// y, faces 0..5 of paint 0 then of paint 1) and, in paint, its paint. A border texel takes the neighbouring
// face's texel at the shared edge: its direction is snapped to the nearest texel centre of the face it
// points into (interior texels are centres already), so the bilinear filter across an edge is GL's
// seamless cube filter (corners: one texel instead of three).
vec3 atlas_texel_direction(ivec2 p, int face_texels, out int paint) {
    int tile = face_texels + 2;
    int block = p.y / tile;  // paint * 6 + face
    paint = block / 6;
    int face = block - 6 * paint;
    int row = p.y - block * tile;
    float a = (2.0 * float(p.x) - 1.0) / float(face_texels) - 1.0;
    float b = (2.0 * float(row) - 1.0) / float(face_texels) - 1.0;
    vec3 r = cube_face_dir(face, a, b);
    vec2 ab;
    int f2 = cube_face_of(r, ab);
    vec2 cell = clamp(floor((ab + 1.0) * (0.5 * float(face_texels))), 0.0, float(face_texels - 1));
    ab = (2.0 * cell + 1.0) / float(face_texels) - 1.0;
    return cube_face_dir(f2, ab.x, ab.y);
}
