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
