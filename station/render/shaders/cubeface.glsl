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
