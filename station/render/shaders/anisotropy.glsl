// Anisotropic Ward gloss by off-specular samples (thesis eqs 2.5.4-2.5.7), the same equations as
// station/render/anisotropy.py (shade_anisotropic), compiled in only when HAS_ANISO = 1:
//   gloss = P_s A(N, V) sum_j W_j S(R_j) / sum_j W_j,  S(R) = sum_i w_i h_i(R.N) C_i(R)  (sum w_i = 1)
//   N_j = cos(t_j) N - sin(t_j) Y,  R_j = reflect(-V, N_j),  t_j evenly over +-2.5 alpha_s
//   W_j = (R_j.N) / sqrt((R_j.N)(V.N)) exp(-2 sin^2 t_j / (alpha_s^2 (1 + cos t_j)))
// u_aniso_w: the isotropic Ward fit of width alpha_x (bound lobe order); u_aniso_albedo: A(N, V) over
// (N.V, azimuth of V from X) (anisotropy.albedo_table), or A = 1 when u_aniso_ward_energy = 0 (energy
// "design"); u_aniso_hint: the tangent hint in the lookup frame.
#if HAS_ANISO
uniform int u_aniso_samples;
uniform float u_aniso_spread;                 // alpha_s = sqrt(alpha_y^2 - alpha_x^2)
uniform float u_aniso_w[N_LOBES];
uniform float u_aniso_ps[2];                  // P_s of each paint (its gloss energy)
uniform vec3 u_aniso_hint;
uniform sampler2D u_aniso_albedo;
uniform float u_aniso_cos_min;
uniform int u_aniso_ward_energy;              // 1: times Ward's albedo A(N, V); 0: A = 1 (the paint's energy)

vec3 aniso_blend(vec3 r, vec3 n) {
    vec3 s = vec3(0.0);
    float rn = clamp(dot(r, n), 0.0, 1.0);
    for (int i = 0; i < N_LOBES; ++i) {
        if (u_aniso_w[i] <= 0.0) continue;
        s += u_aniso_w[i] * horizon(i, rn).y * textureLod(u_lobes[i], r, 0.0).rgb;
        if (LOBE_E[i] < WIDE_EXPONENT) {
            for (int l = 0; l < N_LIGHTS; ++l) {
                if (dot(n, u_light_dir[l]) <= 0.0) continue;
                float e = LOBE_E[i] / (1.0 + LOBE_E[i] * u_light_spread[l]);  // over the light's extent
                s += u_aniso_w[i] * (e + 1.0) / (2.0 * PI) * pow(max(dot(r, u_light_dir[l]), 0.0), e)
                     * u_light_flux[l];
            }
        }
    }
    return s;
}

// n, v, hint in the lookup frame; the gloss of *paint* before the clear coat's factor.
vec3 aniso_gloss(vec3 n, vec3 v, vec3 hint, int paint) {
    vec3 x = hint - dot(hint, n) * n;
    if (length(x) < 1e-6) x = vec3(0.0, 1.0, 0.0) - n.y * n;
    x = normalize(x);
    vec3 y = cross(n, x);
    float vn = max(dot(v, n), 1e-6);
    vec3 acc = vec3(0.0);
    float wsum = 0.0;
    int J = u_aniso_samples;
    for (int j = 0; j < J; ++j) {
        float t = J > 1 ? (-2.5 + 5.0 * float(j) / float(J - 1)) * u_aniso_spread : 0.0;
        vec3 nj = cos(t) * n - sin(t) * y;
        vec3 rj = 2.0 * dot(nj, v) * nj - v;
        float rn = dot(rj, n);
        if (rn <= 0.0) continue;
        float w = rn / sqrt(rn * vn);
        if (u_aniso_spread > 0.0) {
            float st = sin(t);
            w *= exp(-2.0 * st * st / (u_aniso_spread * u_aniso_spread * (1.0 + cos(t))));
        }
        acc += w * aniso_blend(rj, n);
        wsum += w;
    }
    if (u_aniso_ward_energy == 0) return u_aniso_ps[paint] * acc / max(wsum, 1e-30);
    float phi = atan(abs(dot(v, y)), abs(dot(v, x)) + 1e-12);
    vec2 uv = vec2(clamp((vn - u_aniso_cos_min) / (1.0 - u_aniso_cos_min), 0.0, 1.0), phi / (0.5 * PI));
    vec2 size = vec2(textureSize(u_aniso_albedo, 0));
    float albedo = texture(u_aniso_albedo, (uv * (size - 1.0) + 0.5) / size).r;
    return u_aniso_ps[paint] * albedo * acc / max(wsum, 1e-30);
}
#endif
