// Analytic shapes, the same maths as station/render/shapes.py. SHAPE: 0 sphere, 1 cylinder,
// 2 speedshape, 3 panels, 4 seam. hit() returns t (or -1), the unit normal facing the ray, paint id.
const float INF = 1e30;
const float SPEED_NOSE = 0.7, SPEED_TAIL = 1.7, SPEED_H = 0.42, SPEED_W = 0.55;
const float CYL_R = 0.8;
const float SEAM_R = 0.6;
uniform float u_misalign;  // radians, panels only

void take(float t, vec3 n, int paint, inout float best, inout vec3 bn, inout int bp) {
    if (t > 0.0 && t < best) { best = t; bn = n; bp = paint; }
}

void ellipsoid_hits(vec3 o, vec3 d, vec3 axes, float side, int paint, inout float best, inout vec3 bn,
                    inout int bp) {
    vec3 oo = o / axes, dd = d / axes;
    float a = dot(dd, dd), b = dot(dd, oo), c = dot(oo, oo) - 1.0;
    float disc = b * b - a * c;
    if (disc < 0.0) return;
    float root = sqrt(disc);
    for (int k = 0; k < 2; ++k) {
        float t = (-b + (k == 0 ? -root : root)) / a;
        vec3 p = o + t * d;
        if (side * p.x >= 0.0) take(t, p / (axes * axes), paint, best, bn, bp);
    }
}

bool hit(vec3 o, vec3 d, out float t_hit, out vec3 n_hit, out int paint) {
    float best = INF;
    vec3 bn = vec3(0.0, 0.0, 1.0);
    int bp = -1;
#if SHAPE == 0
    float b = dot(d, o), c = dot(o, o) - 1.0, disc = b * b - c;
    if (disc >= 0.0) {
        float t = -b - sqrt(disc);
        vec3 p = o + t * d;
        take(t, p, p.x >= 0.0 ? 1 : 0, best, bn, bp);
    }
#elif SHAPE == 1
    float a = d.x * d.x + d.z * d.z;
    float b = o.x * d.x + o.z * d.z;
    float c = o.x * o.x + o.z * o.z - CYL_R * CYL_R;
    float disc = b * b - a * c;
    if (disc >= 0.0 && a > 1e-12) {
        float t = (-b - sqrt(disc)) / a;
        vec3 p = o + t * d;
        if (abs(p.y) <= 1.0) take(t, vec3(p.x, 0.0, p.z), p.x >= 0.0 ? 1 : 0, best, bn, bp);
    }
    float tc = (1.0 - o.y) / d.y;
    vec3 pc = o + tc * d;
    if (pc.x * pc.x + pc.z * pc.z <= CYL_R * CYL_R) take(tc, vec3(0.0, 1.0, 0.0), pc.x >= 0.0 ? 1 : 0, best, bn, bp);
#elif SHAPE == 2
    ellipsoid_hits(o, d, vec3(SPEED_NOSE, SPEED_H, SPEED_W), -1.0, 0, best, bn, bp);
    ellipsoid_hits(o, d, vec3(SPEED_TAIL, SPEED_H, SPEED_W), 1.0, 1, best, bn, bp);
#elif SHAPE == 3
    vec3 ur = vec3(cos(u_misalign), 0.0, -sin(u_misalign));
    vec3 nr = vec3(sin(u_misalign), 0.0, cos(u_misalign));
    vec3 cs[2] = vec3[2](vec3(-0.52, 0.0, 0.0), vec3(0.02, 0.0, 0.0) + 0.5 * ur);
    vec3 us[2] = vec3[2](vec3(1.0, 0.0, 0.0), ur);
    vec3 ns[2] = vec3[2](vec3(0.0, 0.0, 1.0), nr);
    for (int k = 0; k < 2; ++k) {
        float t = dot(cs[k] - o, ns[k]) / dot(d, ns[k]);
        vec3 rel = o + t * d - cs[k];
        if (abs(dot(rel, us[k])) <= 0.5 && abs(rel.y) <= 0.7) take(t, ns[k], k, best, bn, bp);
    }
#else
    float tf = -o.z / d.z;
    vec3 pf = o + tf * d;
    if (abs(pf.x) <= 1.2 && pf.y >= 0.01 && pf.y <= 0.9) take(tf, vec3(0.0, 0.0, 1.0), 0, best, bn, bp);
    float oz = o.z + SEAM_R;
    float a = d.y * d.y + d.z * d.z;
    float b = o.y * d.y + oz * d.z;
    float c = o.y * o.y + oz * oz - SEAM_R * SEAM_R;
    float disc = b * b - a * c;
    if (disc >= 0.0 && a > 1e-12) {
        float t = (-b - sqrt(disc)) / a;
        vec3 p = o + t * d;
        if (abs(p.x) <= 1.2 && p.y <= -0.01 && p.y >= -0.9 * SEAM_R && p.z >= -SEAM_R)
            take(t, vec3(0.0, p.y, p.z + SEAM_R), 1, best, bn, bp);
    }
#endif
    t_hit = best;
    n_hit = normalize(bn);
    if (dot(n_hit, d) > 0.0) n_hit = -n_hit;
    paint = bp;
    return bp >= 0;
}
