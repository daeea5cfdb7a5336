// Shadow maps of the strongest extracted lights and the ground's ambient occlusion
// (station/render/gl_shadows.py, module docstring). N_SHADOW maps (0 ... 2) for the lights SHADOW_L0,
// SHADOW_L1 (indices into u_light_dir; -1: none); HAS_AO: the ground's sky share from u_ao.
#ifndef N_SHADOW
#define N_SHADOW 0
#endif
#ifndef SHADOW_L0
#define SHADOW_L0 -1
#define SHADOW_L1 -1
#endif
#ifndef HAS_AO
#define HAS_AO 0
#endif
#if HAS_AO
uniform sampler2D u_ao;  // occluded fraction O over the ground disc's square
#endif
#if N_SHADOW > 0
uniform mat4 u_shadow_mat[N_SHADOW];  // world -> (u, v, depth) in [0, 1]^3 of each light's map
uniform vec3 u_shadow_par[N_SHADOW];  // (world texel, world depth over 0..1, tan of the light's radius)
uniform sampler2DShadow u_shadow_cmp[N_SHADOW];
uniform sampler2D u_shadow_raw[N_SHADOW];
uniform sampler2D u_shadow_esm[N_SHADOW];  // the model's exponential shadow maps: L, exp(c L) box-filtered
uniform float u_shadow_c[N_SHADOW];  // their sharpness c per unit of map depth
// Taps on the unit disc (Vogel spiral of 8, golden angle) of the ground's lookup.
const vec2 SHADOW_TAPS[8] = vec2[8](
    vec2(0.2500, 0.0000), vec2(-0.3417, 0.3129), vec2(0.0539, -0.5565), vec2(0.4258, 0.5183),
    vec2(-0.7696, -0.1358), vec2(0.6914, -0.4868), vec2(-0.2090, 0.8945), vec2(-0.5201, -0.8112));

// The ground's visibility in [0, 1] of a light from world point p of unit normal nw (cos_l = nw . l): the
// blocker search (4 gathers of 4 depths) and the percentage-closer filter (8 bilinear comparisons) of
// station/render/gl_shadows.py; baked once per light and model (GLRenderer._ground_map).
float shadow_lookup(sampler2DShadow cmp, sampler2D raw, mat4 m, vec3 par, vec3 p, vec3 nw, float cos_l) {
    float sin_l = sqrt(max(1.0 - cos_l * cos_l, 0.0));
    vec3 q = p + nw * (SHADOW_NORMAL_OFFSET * par.x * (1.0 + sin_l));
    vec3 s = (m * vec4(q, 1.0)).xyz;
    if (s.x <= 0.0 || s.y <= 0.0 || s.x >= 1.0 || s.y >= 1.0) return 1.0;
    float texel_uv = 1.0 / float(textureSize(raw, 0).x);
    float ref = min(s.z, 1.0);
    // blocker search over the light's disc seen from p, as far as the box's near side
    float search = clamp(s.z * par.y * par.z / par.x, 1.0, SHADOW_MAX_RADIUS) * texel_uv;
    float blockers = 0.0, count = 0.0;
    for (int i = 0; i < 4; ++i) {
        vec4 d = textureGather(raw, s.xy + SHADOW_TAPS[2 * i + 1] * search);
        vec4 hit = vec4(lessThan(d, vec4(ref)));
        blockers += dot(hit, d);
        count += dot(hit, vec4(1.0));
    }
    if (count == 0.0) return 1.0;
    float dist = (ref - blockers / count) * par.y;  // receiver to blockers, world units along the light
    float radius = clamp(dist * par.z / par.x, 1.0, SHADOW_MAX_RADIUS);
    // the receiver's plane tilts across the filter: a depth bias of the radius times the slope
    float bias = par.x * (1.0 + radius * min(sin_l / max(cos_l, 0.1), 4.0)) / par.y;
    float vis = 0.0;
    for (int i = 0; i < 8; ++i)
        vis += texture(cmp, vec3(s.xy + SHADOW_TAPS[i] * radius * texel_uv, ref - bias));
    return vis / 8.0;
}

#if BAKE_GROUND
// A wide light's disc (station/render/gl_shadows.py, DISC_MIN_DEG; DISC_DIRECTIONS, DISC_COLUMNS and
// DISC_ROWS from its shadow_defines): DISC_DIRECTIONS depth maps tiled DISC_COLUMNS across in
// u_shadow_disc[k], u_shadow_disc_mat their views; u_shadow_disc_par[k] (world texel, world depth over
// 0..1, tan of the light's radius when it has a disc else 0).
uniform sampler2DShadow u_shadow_disc[N_SHADOW];
uniform mat4 u_shadow_disc_mat[N_SHADOW * DISC_DIRECTIONS];
uniform vec3 u_shadow_disc_par[N_SHADOW];
uniform vec4 u_shadow_bound;  // the caster's bounding sphere (world centre, radius)

// The ground's visibility of light slot k's disc from p (unit normal nw, cos_l = nw . l): the share of the
// disc's directions whose depth map does not hide p (each a bilinear 2 x 2 comparison), the receiver moved
// off its surface as for shadow_lookup.
float disc_lookup(sampler2DShadow atlas, int k, vec3 par, vec3 p, vec3 nw, vec3 lw, float cos_l) {
    // the cone of the light's directions from p (half angle: its radius, tan in par.z) misses the caster's
    // bounding sphere: nothing to look up
    vec3 to_c = u_shadow_bound.xyz - p;
    float dc = length(to_c);
    if (dc > u_shadow_bound.w) {
        float apart = acos(clamp(dot(to_c / dc, lw), -1.0, 1.0)) - asin(u_shadow_bound.w / dc);
        if (apart > atan(par.z)) return 1.0;
    }
    float sin_l = sqrt(max(1.0 - cos_l * cos_l, 0.0));
    vec3 q = p + nw * (SHADOW_NORMAL_OFFSET * par.x * (1.0 + sin_l));
    float bias = par.x * (1.0 + min(sin_l / max(cos_l, 0.1), 4.0)) / par.y;
    float vis = 0.0;
    for (int j = 0; j < DISC_DIRECTIONS; ++j) {
        vec3 s = (u_shadow_disc_mat[k * DISC_DIRECTIONS + j] * vec4(q, 1.0)).xyz;
        if (s.x <= 0.0 || s.y <= 0.0 || s.x >= 1.0 || s.y >= 1.0) {
            vis += 1.0;
        } else {
            vec2 tile = vec2(float(j % DISC_COLUMNS), float(j / DISC_COLUMNS));
            vis += texture(atlas, vec3((tile + s.xy) / vec2(float(DISC_COLUMNS), float(DISC_ROWS)), min(s.z, 1.0) - bias));
        }
    }
    return vis / float(DISC_DIRECTIONS);
}
#endif

// The model's visibility of a light (one lookup): exp(c (L - z)) clamped to 1, L the exponential shadow
// map's log-filtered depth and z the receiver's depth, the receiver moved off its surface as above.
float esm_lookup(sampler2D esm, float c, mat4 m, vec3 par, vec3 p, vec3 nw, float cos_l) {
    float sin_l = sqrt(max(1.0 - cos_l * cos_l, 0.0));
    vec3 s = (m * vec4(p + nw * (SHADOW_NORMAL_OFFSET * par.x * (1.0 + sin_l)), 1.0)).xyz;
    if (s.x <= 0.0 || s.y <= 0.0 || s.x >= 1.0 || s.y >= 1.0) return 1.0;
    return clamp(exp(c * (textureLod(esm, s.xy, 0.0).r - min(s.z, 1.0))), 0.0, 1.0);
}

// Visibility of light l (world direction lw) at p, normal nw: its map when it has one, else 1.
float light_shadow(int l, vec3 p, vec3 nw, vec3 lw) {
    float c = dot(nw, lw);
#if BAKE_GROUND
    if (l == SHADOW_L0) {
        if (u_shadow_disc_par[0].z > 0.0) return disc_lookup(u_shadow_disc[0], 0, u_shadow_disc_par[0], p, nw, lw, c);
        return shadow_lookup(u_shadow_cmp[0], u_shadow_raw[0], u_shadow_mat[0], u_shadow_par[0], p, nw, c);
    }
#if N_SHADOW > 1
    if (l == SHADOW_L1) {
        if (u_shadow_disc_par[1].z > 0.0) return disc_lookup(u_shadow_disc[1], 1, u_shadow_disc_par[1], p, nw, lw, c);
        return shadow_lookup(u_shadow_cmp[1], u_shadow_raw[1], u_shadow_mat[1], u_shadow_par[1], p, nw, c);
    }
#endif
#else
    if (l == SHADOW_L0) return esm_lookup(u_shadow_esm[0], u_shadow_c[0], u_shadow_mat[0], u_shadow_par[0], p, nw, c);
#if N_SHADOW > 1
    if (l == SHADOW_L1) return esm_lookup(u_shadow_esm[1], u_shadow_c[1], u_shadow_mat[1], u_shadow_par[1], p, nw, c);
#endif
#endif
    return 1.0;
}
#endif

// Whether light l casts a shadow map in this frame.
bool has_shadow_map(int l) {
    return N_SHADOW > 0 && (l == SHADOW_L0 || (N_SHADOW > 1 && l == SHADOW_L1));
}

#ifndef SHADOW_PROBE
#define SHADOW_PROBE 0
#endif
#if SHADOW_PROBE
// Diagnostics (GLRenderer.shadow_probe): (visibility of light SHADOW_L0, of SHADOW_L1, 1 - O) at world point
// p of world normal nw; 1 where a light has no map, or O where there is no AO map.
vec3 shadow_probe(vec3 p, vec3 nw) {
    vec3 out_v = vec3(1.0);
#if N_SHADOW > 0
    vec3 l0 = u_light_world[SHADOW_L0];
    out_v.x = light_shadow(SHADOW_L0, p, nw, l0);
#endif
#if N_SHADOW > 1
    vec3 l1 = u_light_world[SHADOW_L1];
    out_v.y = light_shadow(SHADOW_L1, p, nw, l1);
#endif
#if HAS_AO
    out_v.z = 1.0 - textureLod(u_ao, 0.5 * (p.xz - u_ground_c) / u_ground_radius + 0.5, 0.0).r;
#endif
    return out_v;
}
#endif
