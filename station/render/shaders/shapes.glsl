// Analytic shapes, the same maths as station/render/shapes.py. SHAPE: 0 sphere, 1 cylinder,
// 2 speedshape, 3 panels, 4 seam. hit() returns t (or -1), the unit normal facing the ray, paint id.
const float INF = 1e30;
const float SPEED_A = 1.4, SPEED_H = 0.45, SPEED_W = 0.6, SPEED_K = 0.3;
const float CYL_R = 0.8;
const int SPEED_STEPS = 24, SPEED_BISECTIONS = 14;
const float SEAM_R = 0.6;
uniform float u_misalign;  // radians, panels only

void take(float t, vec3 n, int paint, inout float best, inout vec3 bn, inout int bp) {
    if (t > 0.0 && t < best) { best = t; bn = n; bp = paint; }
}

float speed_f(vec3 p) {
    float s = 1.0 - SPEED_K * p.x / SPEED_A;
    float q = (p.y / SPEED_H) * (p.y / SPEED_H) + (p.z / SPEED_W) * (p.z / SPEED_W);
    return (p.x / SPEED_A) * (p.x / SPEED_A) + q / (s * s) - 1.0;
}

vec3 speed_grad(vec3 p) {
    float s = 1.0 - SPEED_K * p.x / SPEED_A;
    float q = (p.y / SPEED_H) * (p.y / SPEED_H) + (p.z / SPEED_W) * (p.z / SPEED_W);
    return vec3(2.0 * p.x / (SPEED_A * SPEED_A) + 2.0 * q * SPEED_K / (SPEED_A * s * s * s),
                2.0 * p.y / (SPEED_H * SPEED_H * s * s),
                2.0 * p.z / (SPEED_W * SPEED_W * s * s));
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
    vec3 ext = vec3(SPEED_A, SPEED_H * (1.0 + SPEED_K), SPEED_W * (1.0 + SPEED_K));
    vec3 inv = 1.0 / d;
    vec3 t0 = (-ext - o) * inv, t1 = (ext - o) * inv;
    vec3 tmin = min(t0, t1), tmax = max(t0, t1);
    float tn = max(max(max(tmin.x, tmin.y), tmin.z), 0.0);
    float tf = min(min(tmax.x, tmax.y), tmax.z);
    if (tf > tn) {
        float dt = (tf - tn) / float(SPEED_STEPS);
        float lo = tn, hi = tn;
        bool found = false;
        for (int k = 1; k <= SPEED_STEPS; ++k) {
            float t = tn + float(k) * dt;
            if (speed_f(o + t * d) < 0.0) { lo = t - dt; hi = t; found = true; break; }
        }
        if (found) {
            for (int k = 0; k < SPEED_BISECTIONS; ++k) {
                float mid = 0.5 * (lo + hi);
                if (speed_f(o + mid * d) < 0.0) hi = mid; else lo = mid;
            }
            float t = 0.5 * (lo + hi);
            vec3 p = o + t * d;
            take(t, speed_grad(p), p.x >= 0.0 ? 1 : 0, best, bn, bp);
        }
    }
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
