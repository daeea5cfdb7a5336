#version 430
// Lobe-blend shading (thesis eqs 2.5.1-2.5.3), the same equation as station/render/numpy_renderer.py:
//   radiance = wd * D(N) + sum_i (h_i(R.N) wg_i + g_i(R.N) wdd_i) * C_i(R)
// with (g_i, h_i) read from the horizon table u_horizon (HORIZON_N columns; rows of g alone, four lobes a
// row, then rows of (g, h) pairs: gl_textures.horizon_texture); with BENT_DD (1) the
// directionally diffuse term of a wide lobe reads C_i at B = normalize(E_i R + COSINE_SG N). The lobes are
// bound with the N_WIDE wide ones (horizon table) first; the narrow ones have (g, h) = (R.N, 1)
// exactly and, when COMBINED, are pre-summed per paint into an atlas (shaders/atlas.glsl), so only the
// wide ones are looked up per lobe here.
// with the weights already converted to normalised maps (LobeWeights.map_weights). Two paints:
// index 0/1 from the shape. Defines: SHAPE, N_LOBES, OUTPUT_LINEAR (1: float radiance out),
// DIFFUSE_SH (1: 9-coefficient SH instead of the exponent-1 cube), COMBINED (1: the narrow lobes of
// both paints pre-summed into a gloss and a directionally-diffuse atlas, shaders/combine.frag.glsl).
// MESH (1): shade the fragments of a rasterised mesh (shaders/mesh.vert.glsl) instead of ray casting a
// shape; NO_SHAPE (1): nothing to hit, the stage only (the backdrop pass under a mesh). Mesh parts whose
// material code v_painted is not MAT_PAINT are drawn by part_radiance (grey, tyre, glass, chrome).
// HAS_COAT, HAS_STAGE, HAS_FLAKES (0/1): compile the clear coat, the stage and the flakes in only when a
// frame uses them (llvmpipe pays for code behind uniform branches).
// HAS_ANISO (0/1): the gloss of both paints is anisotropic Ward by off-specular samples
// (shaders/anisotropy.glsl); the caller then passes the paints' own gloss weights as zero.
#ifndef MESH
#define MESH 0
#endif
// MESH_PARTS: which of a mesh's triangles the program draws: 0 all (the paint and the neutral parts, told
// apart per fragment), 1 the paint's alone, 2 the neutral parts' alone (station/render/gl_passes.py draws
// the two sorted ranges with the two programs, so a fragment pays for its own material's code only).
#ifndef MESH_PARTS
#define MESH_PARTS 0
#endif
#ifndef HAS_COAT
#define HAS_COAT 1
#endif
#ifndef HAS_STAGE
#define HAS_STAGE 1
#endif
#ifndef HAS_FLAKES
#define HAS_FLAKES 1
#endif
#ifndef HAS_ANISO
#define HAS_ANISO 0
#endif
#ifndef HORIZON_CHEB_MASK
#define HORIZON_CHEB_MASK 0
#endif
#ifndef NO_SHAPE
#define NO_SHAPE 0
#endif
// SMOOTH_OUT (0/1): the coarse pass of a frame (GLRenderer.coarse_smooth): the smooth terms of the paint
// (smooth_terms) at the pixel's hit, gloss part to f_color, the rest to f_dd (zero where the ray misses).
// SMOOTH_IN (0/1): read them back bilinearly (u_smooth_g, u_smooth_dd) instead of computing them: drawn
// only where every ray hits and every coarse sample the bilinear read takes hits too (INSIDE_SHAPE).
#ifndef SMOOTH_OUT
#define SMOOTH_OUT 0
#endif
#ifndef SMOOTH_IN
#define SMOOTH_IN 0
#endif
// INSIDE_SHAPE (0/1): the program is drawn only where every ray hits the shape (station.render.footprint),
// so the background is compiled out.
#ifndef INSIDE_SHAPE
#define INSIDE_SHAPE 0
#endif
// WIDE_GLOSS_MASK: bit i set when bound wide lobe i carries gloss in either paint; NARROW_DD (0/1): a
// narrow lobe carries a directionally diffuse weight. Zero-weight terms are compiled out
// (GLRenderer._terms): exact, since they add nothing.
#ifndef WIDE_GLOSS_MASK
#define WIDE_GLOSS_MASK -1
#endif
#ifndef NARROW_DD
#define NARROW_DD 1
#endif
#ifndef N_OCC
#define N_OCC 0
#endif
#ifndef BAKE_GROUND
#define BAKE_GROUND 0
#endif
#ifndef HAS_FALL_OFF
#define HAS_FALL_OFF 0
#endif
#ifndef FLAKE_CELL_PIXELS
#define FLAKE_CELL_PIXELS 4.0
#endif
#ifndef FLAKE_GLINT_RADIUS
#define FLAKE_GLINT_RADIUS 0.5
#endif
#ifndef FLAKE_WINDOW_NORM
#define FLAKE_WINDOW_NORM 4.151
#endif
#ifndef STAGE_BACKDROP
#define STAGE_BACKDROP 0
#endif
#ifndef STAGE_GROUND
#define STAGE_GROUND 0
#endif
#ifndef BACKDROP_LIGHTS
#define BACKDROP_LIGHTS 0
#endif
#ifndef PENUMBRA_DEG
#define PENUMBRA_DEG 1.0
#endif
#ifndef BENT_DD
#define BENT_DD 0
#endif
#ifndef COSINE_SG
#define COSINE_SG 2.133
#endif
#ifndef NEUTRAL_ALBEDO
#define NEUTRAL_ALBEDO 0.18
#endif
// DIFFUSE_ATLAS: under a clear coat both paints' diffuse base, pi K_A D + pi K_D D_coat, is read from one
// atlas pre-mixed per paint (u_diffuse_base, shaders/combine_diffuse.frag.glsl) instead of the two maps;
// not with the aspecular fall-off, which needs D(N) itself.
#define DIFFUSE_ATLAS (COMBINED && HAS_COAT && !DIFFUSE_SH && !HAS_FALL_OFF)
// Mesh material codes (station.render.meshes) and the neutral parts' constants.
#ifndef MAT_PAINT
#define MAT_PAINT 1.0
#define MAT_TYRE 2.0
#define MAT_GLASS 3.0
#define MAT_CHROME 4.0
#define TYRE_ALBEDO 0.03
#define GLASS_INTERIOR 0.03
#endif
//#include shapes.glsl
//#include tonemap.glsl
uniform vec3 u_eye, u_forward, u_right, u_up;
uniform float u_tan_half_fov, u_aspect;
uniform vec2 u_size;
uniform samplerCube u_lobes[N_LOBES];
uniform sampler2D u_horizon;
// LOBE_EXPONENTS: the exponents in bound order; N_LIGHTS: the lights taken out of the wide lobes' maps
// (both fixed per renderer, compiled in so the loops below unroll with constant indices).
const float LOBE_E[N_LOBES] = float[N_LOBES](LOBE_EXPONENTS);
uniform vec3 u_light_dir[MAX_LIGHTS];
uniform vec3 u_light_world[MAX_LIGHTS];  // the same directions in the world (u_rot's transpose applied once a frame)
uniform vec3 u_light_flux[MAX_LIGHTS];
uniform float u_light_spread[MAX_LIGHTS];  // angular spread s^2 (rad^2): lobes smoothed to E / (1 + E s^2)
const float PI = 3.14159265358979;
#if COMBINED
uniform sampler2D u_gloss, u_dd;  // both paints' pre-summed narrow lobes (atlas.glsl)
//#include atlas.glsl
#endif
uniform samplerCube u_diffuse;
uniform vec3 u_sh[9];
uniform vec3 u_wd[2];
uniform vec3 u_wdd[2 * N_LOBES];
uniform float u_wg[2 * N_LOBES];
uniform vec3 u_background;
// Clear coat (station.model.gloss.ClearCoat): gloss terms times F(N.V)/u_coat_ref (exact dielectric F of the
// coat's index u_coat_n, shaders/coat.glsl), base terms times 1 - F(N.V); compiled in (HAS_COAT) only for a
// frame with a coat; without it the thesis's model. u_coat_t = 1 - F_dr,ext: the entry weight's denominator.
uniform float u_coat_n, u_coat_ref, u_coat_t;
// The coat's diffuse base: pi K_D (u_wk) reads the coat-transmitted diffuse map u_diffuse_coat (the light
// entering the coat weighted by (1 - F(N.l))/(1 - F_dr,ext), prefilter.coat_diffuse_map) or its SH twin
// u_sh_coat; pi K_A (the rest of u_wd) and the effect terms keep u_diffuse (ClearCoat's docstring).
uniform samplerCube u_diffuse_coat;
uniform sampler2D u_diffuse_base;  // DIFFUSE_ATLAS: pi K_A D + pi K_D D_coat per paint (atlas.glsl layout)
uniform vec3 u_wk[2];
uniform vec3 u_sh_coat[9];
// Stage (station/render/stage.py): lookups at u_rot * d (environment turned about +Y), the backdrop
// lobe map u_backdrop (exponent u_backdrop_exp, its lights added when BACKDROP_LIGHTS), the ground disc
// at height u_ground_y about u_ground_c with contact shadow from N_OCC sphere proxies u_occ (xyz, r)
// (N_OCC compiled in: the loops unroll), baked into u_ground_map (ground_radiance).
uniform mat3 u_rot;
// STAGE_BACKDROP, STAGE_GROUND, BACKDROP_LIGHTS (0/1): compiled in per stage (the frame's stage options).
uniform samplerCube u_backdrop;
uniform float u_backdrop_exp, u_ground_y, u_ground_albedo, u_ground_radius;
uniform sampler2D u_ground_map;
uniform vec2 u_ground_c;
uniform vec4 u_occ[8];
// Flakes (station/render/flakes.py): one random flake normal per surface cell of two levels of a fixed
// hierarchy; zero-mean sparkle tint * reflectance * sum_k w_k (L_sharp(R_m,k) - C_E(R)).
uniform samplerCube u_flake_sharp, u_flake_mean;
uniform float u_flake_size_mm, u_flake_density, u_flake_sigma, u_flake_reflectance, u_unit_mm;
uniform mat3 u_flake_lattice;  // the cell lattice's rotation (flakes.LATTICE_ROTATION)
uniform vec3 u_flake_tint[2];
#ifndef N_SHADOW
#define N_SHADOW 0
#endif
#ifndef SHADOWED_MAPS
#define SHADOWED_MAPS 0
#endif
#if N_SHADOW > 0 && SHADOWED_MAPS
// The maps that keep the whole environment without shadowed light SHADOW_Lj (station/render/gl_light_maps.py):
// both paints' narrow gloss and directionally diffuse sums (atlases), the glint map and the flakes' mean map.
// A point that has lost lost_j = 1 - V_j of the lights reads X (1 - sum lost_j) + sum lost_j X_j.
uniform sampler2D u_shadowed_gloss[N_SHADOW], u_shadowed_dd[N_SHADOW];
uniform samplerCube u_shadowed_glint[N_SHADOW], u_shadowed_mean[N_SHADOW];
#endif
#if SMOOTH_OUT
layout(location = 0) out vec4 f_color;
layout(location = 1) out vec4 f_dd;
#else
out vec4 f_color;
#endif
#if SMOOTH_IN
uniform sampler2D u_smooth_g, u_smooth_dd;
#endif

uvec3 pcg3d(uvec3 v) {
    v = v * 1664525u + 1013904223u;
    v.x += v.y * v.z; v.y += v.z * v.x; v.z += v.x * v.y;
    v ^= v >> 16u;
    v.x += v.y * v.z; v.y += v.z * v.x; v.z += v.x * v.y;
    return v;
}

// One cell level k of the flake hierarchy at lattice point q (the point in cells of side FLAKE_SIZE 2^k, fixed
// on the surface: world = object space, the shapes and meshes never move), its cells holding *count* flakes
// on average: the cell hashed to a flake normal and, where it holds fewer than one flake on average, to
// whether it holds one (station.render.flakes.flake_levels). The lattice is turned against the scene's axes
// and the cell's term weighted by a bump about its centre that vanishes on its faces, so a glint is a soft
// spot and the sparkle continuous from cell to cell (flakes.flake_window). Returns the level's weight before
// the blend and, in rm, the view mirrored about the flake.
float flake_level(vec3 q, int k, float count, vec3 n, vec3 t, vec3 b, vec3 ve, out vec3 rm) {
    vec3 x = fract(q) - 0.5;  // offset from the cell's centre: the glint bump (flakes.flake_window)
    float bump = max(1.0 - dot(x, x) / (FLAKE_GLINT_RADIUS * FLAKE_GLINT_RADIUS), 0.0);
    uvec3 h = pcg3d(uvec3(ivec3(floor(q)) + ivec3(1 << 20)) + uvec3(0u, 0u, uint(k) << 24u));
    vec3 u = (vec3(ivec3(h >> 8u)) + 0.5) / 16777216.0;  // 24 bits: a signed conversion is exact
    float a = 2.0 * PI * u.y;
    vec2 g = sqrt(-2.0 * log(u.x)) * vec2(cos(a), sin(a));
    vec3 m = normalize(n + u_flake_sigma * (g.x * t + g.y * b));
    rm = 2.0 * dot(m, ve) * m - ve;
    return float(u.z < count) / sqrt(max(count, 1.0)) * bump * bump;
}

vec3 flake_sparkle(vec3 p, float dist, float ndv, vec3 n, vec3 ve, vec3 r, int paint, vec2 lost) {
    // Multiscale cells (Zirr & Kaplanyan 2016's hierarchy, station.render.flakes): the level whose cells
    // match the pixel's footprint on the surface (side / sqrt(N.V)), blended with the next coarser one
    // by the fractional level, so the sparkle sticks to the surface and changes smoothly with distance.
    float px = FLAKE_CELL_PIXELS * 2.0 * dist * u_tan_half_fov / u_size.y * u_unit_mm / sqrt(max(ndv, 0.05));
    float lam = max(log2(px / u_flake_size_mm), 0.0);
    int k = int(floor(lam));
    float f = lam - float(k);
    vec3 t = normalize(abs(n.y) < 0.9 ? cross(n, vec3(0.0, 1.0, 0.0)) : cross(n, vec3(1.0, 0.0, 0.0)));
    vec3 b = cross(n, t);
    // Level k + 1 has cells twice as wide: its lattice point is half level k's and its count four times
    // (powers of two: exactly what the level's own side gives).
    float c = ldexp(u_flake_size_mm, k);
    float count = u_flake_density * c * c;
    vec3 q = u_flake_lattice * p * (u_unit_mm / c);
    vec3 rm0, rm1;
    float norm = FLAKE_WINDOW_NORM / sqrt((1.0 - f) * (1.0 - f) + f * f);  // the blend keeps the variance
    float w0 = flake_level(q, k, count, n, t, b, ve, rm0) * ((1.0 - f) * norm);
    float w1 = flake_level(0.5 * q, k + 1, 4.0 * count, n, t, b, ve, rm1) * (f * norm);
    // Both glint lookups and the mean's are made for every pixel: llvmpipe evaluates both sides of a
    // divergent branch, so a test on the weights would add work, not save it. Reflections below the
    // horizon are zero (a select, no branch).
    float up0 = float(dot(rm0, n) > 0.0) * w0, up1 = float(dot(rm1, n) > 0.0) * w1;
    vec3 glint = up0 * textureLod(u_flake_sharp, rm0, 0.0).rgb + up1 * textureLod(u_flake_sharp, rm1, 0.0).rgb;
    vec3 mean_map = textureLod(u_flake_mean, r, 0.0).rgb;
#if N_SHADOW > 0 && SHADOWED_MAPS
    // a shadowed light's glints are gone, and so is its part of their mean (station/render/gl_light_maps.py)
    if (lost.x + lost.y > 0.0) {
        float kept = 1.0 - lost.x - lost.y;
        glint *= kept;
        mean_map *= kept;
        glint += lost.x * (up0 * textureLod(u_shadowed_glint[0], rm0, 0.0).rgb
                           + up1 * textureLod(u_shadowed_glint[0], rm1, 0.0).rgb);
        mean_map += lost.x * textureLod(u_shadowed_mean[0], r, 0.0).rgb;
#if N_SHADOW > 1
        glint += lost.y * (up0 * textureLod(u_shadowed_glint[1], rm0, 0.0).rgb
                           + up1 * textureLod(u_shadowed_glint[1], rm1, 0.0).rgb);
        mean_map += lost.y * textureLod(u_shadowed_mean[1], r, 0.0).rgb;
#endif
    }
#endif
    // C_E(R): the sharp map prefiltered with the flakes' reflected lobe (flakes.flake_mean_cube), times the
    // fraction of the flakes' reflections above the horizon, Phi(asin(N.V) / (2 sigma)) (flakes.flake_horizon,
    // erf by Abramowitz & Stegun 7.1.26).
    float z = asin(clamp(ndv, 0.0, 1.0)) / (2.0 * u_flake_sigma) / sqrt(2.0);
    float et = 1.0 / (1.0 + 0.3275911 * z);
    float poly = et * (0.254829592 + et * (-0.284496736 + et * (1.421413741 + et * (-1.453152027 + et * 1.061405429))));
    vec3 mean = mean_map * (1.0 - 0.5 * poly * exp(-z * z));
    vec3 tint = paint == 0 ? u_flake_tint[0] : u_flake_tint[1];
    return tint * u_flake_reflectance * (glint - (w0 + w1) * mean);
}

//#include coat.glsl

// Exact unpolarised dielectric Fresnel F(N.V) of the coat (station.model.fresnel.fresnel_dielectric, coat.glsl);
// 1 at grazing, never more.
float coat_fresnel(float ndv) {
    return dielectric_fresnel(ndv, u_coat_n);
}

// The horizon table's rows (gl_textures.horizon_texture): HORIZON_G_ROWS rows of g alone (four lobes a
// row), then the (g, h) pairs.
const int HORIZON_G_ROWS = (N_LOBES + 3) / 4;
const int HORIZON_ROWS = HORIZON_G_ROWS + (N_LOBES + 1) / 2;

vec4 horizon_row(int row, float c) {
    return texture(u_horizon, vec2((c * float(HORIZON_N - 1) + 0.5) / float(HORIZON_N),
                                   (float(row) + 0.5) / float(HORIZON_ROWS)));
}

// (g, h) of bound lobe i at c = R.N: lobes 2k and 2k+1 share a pair row (.rg, .ba), so with a constant i
// the two lookups of a pair are one.
vec2 horizon(int i, float c) {
    vec4 t = horizon_row(HORIZON_G_ROWS + i / 2, c);
    return (i % 2 == 0) ? t.rg : t.ba;
}

// g of bound lobe i at c = R.N alone: lobes 4k..4k+3 share a row, so with a constant i four lookups are one.
float horizon_g(int i, float c) {
    return horizon_row(i / 4, c)[i % 4];
}

// g of bound lobe i from its Chebyshev polynomial in x = 2c - 1 (station.render.horizon_poly: compiled in
// for the lobes of HORIZON_CHEB_MASK, whose polynomial is as close to g as the table), by Clenshaw's
// recurrence: arithmetic instead of a lookup.
#if HORIZON_CHEB_MASK != 0
const float HORIZON_CHEB_C[N_LOBES * (HORIZON_DEGREE + 1)] = float[](HORIZON_CHEB);
float horizon_cheb(int i, float c) {
    float x = 2.0 * c - 1.0, b1 = 0.0, b2 = 0.0;
    for (int k = HORIZON_DEGREE; k >= 1; --k) {
        float b0 = HORIZON_CHEB_C[i * (HORIZON_DEGREE + 1) + k] + 2.0 * x * b1 - b2;
        b2 = b1;
        b1 = b0;
    }
    return HORIZON_CHEB_C[i * (HORIZON_DEGREE + 1)] + x * b1 - b2;
}
#endif

// g of bound wide lobe i at c: its polynomial where HORIZON_CHEB_MASK has it, else its row of g alone
// (i is constant in the unrolled lobe loop, so the test is resolved at compile time).
float wide_g(int i, float c) {
#if HORIZON_CHEB_MASK != 0
    if (((HORIZON_CHEB_MASK >> i) & 1) != 0) return horizon_cheb(i, c);
#endif
    return horizon_g(i, c);
}

vec3 sh_eval_with(vec3 c[9], vec3 n) {
    return c[0] * 0.282095 + c[1] * (0.488603 * n.y) + c[2] * (0.488603 * n.z)
         + c[3] * (0.488603 * n.x) + c[4] * (1.092548 * n.x * n.y) + c[5] * (1.092548 * n.y * n.z)
         + c[6] * (0.315392 * (3.0 * n.z * n.z - 1.0)) + c[7] * (1.092548 * n.x * n.z)
         + c[8] * (0.546274 * (n.x * n.x - n.y * n.y));
}

vec3 sh_eval(vec3 n) {
    return sh_eval_with(u_sh, n);
}

//#include shadows.glsl

// Radiance of the white ground at p, per unit albedo (station.render.stage.ground_radiance): the rest of
// the sky (the diffuse map at +Y less the extracted lights' direct parts) with the contact shadow of the
// sphere proxies, plus each light's direct part times its visibility past them. View-independent: baked
// once per stage into a texture over the disc (BAKE_GROUND), which the frame looks up.
vec3 ground_radiance(vec3 p) {
    float open_sky = 1.0;  // the product of each proxy's unoccluded share (station.render.stage.sphere_occlusion)
    for (int k = 0; k < N_OCC; ++k) {
        vec3 v = u_occ[k].xyz - p;
        float r2 = u_occ[k].w * u_occ[k].w;
        float d2 = max(dot(v, v), r2);
        open_sky *= 1.0 - r2 / d2 * clamp(v.y / sqrt(d2), 0.0, 1.0);
    }
#if HAS_AO
    open_sky = 1.0 - textureLod(u_ao, 0.5 * (p.xz - u_ground_c) / u_ground_radius + 0.5, 0.0).r;
#endif
#if DIFFUSE_SH
    vec3 sky = sh_eval(vec3(0.0, 1.0, 0.0));
#else
    vec3 sky = textureLod(u_diffuse, vec3(0.0, 1.0, 0.0), 0.0).rgb;
#endif
    vec3 lit = vec3(0.0);
    vec3 direct_sum = vec3(0.0);
    float pw = radians(PENUMBRA_DEG);
    for (int l = 0; l < N_LIGHTS; ++l) {
        vec3 ld = u_light_world[l];
        if (ld.y <= 0.0) continue;
        vec3 direct = ld.y * u_light_flux[l] / PI;
        direct_sum += direct;
        float vis = 1.0;
#if N_SHADOW > 0
        if (has_shadow_map(l)) vis = light_shadow(l, p, vec3(0.0, 1.0, 0.0), ld); else
#endif
        for (int k = 0; k < N_OCC; ++k) {
            vec3 v = u_occ[k].xyz - p;
            float dl = max(length(v), u_occ[k].w * (1.0 + 1e-6));
            float alpha = asin(clamp(u_occ[k].w / dl, 0.0, 1.0));
            float beta = acos(clamp(dot(v, ld) / dl, -1.0, 1.0));
            float xs = clamp((beta - (alpha - pw)) / (2.0 * pw), 0.0, 1.0);
            vis *= xs * xs * (3.0 - 2.0 * xs);
        }
        lit += direct * vis;
    }
    vec3 rest = max(sky - direct_sum, vec3(0.0));
    return rest * clamp(open_sky, 0.0, 1.0) + lit;
}

vec3 stage_background(vec3 o, vec3 d) {
    vec3 bg = u_background;
#if STAGE_BACKDROP
    vec3 de = u_rot * d;
    bg = textureLod(u_backdrop, de, 0.0).rgb;
#if BACKDROP_LIGHTS
    float e = u_backdrop_exp;
    for (int l = 0; l < N_LIGHTS; ++l)
        bg += (e + 1.0) / (2.0 * PI) * pow(max(dot(de, u_light_dir[l]), 0.0), e) * u_light_flux[l];
#endif
#endif
#if STAGE_GROUND
    if (d.y < -1e-9) {
        float t = (u_ground_y - o.y) / d.y;
        if (t > 0.0) {
            vec3 p = o + t * d;
            vec2 q = (p.xz - u_ground_c) / u_ground_radius;  // the disc in [-1, 1]^2
            float x = clamp((length(q) - 0.5) / 0.5, 0.0, 1.0);
            float w = 1.0 - x * x * (3.0 - 2.0 * x);
            // the ground's radiance before its albedo, baked per stage into u_ground_map (GLRenderer._ground_map)
            bg = mix(bg, u_ground_albedo * textureLod(u_ground_map, 0.5 * q + 0.5, 0.0).rgb, w);
        }
    }
#endif
    return bg;
}

#if HAS_FALL_OFF
// Aspecular fall-off (station.render.weights, numpy_renderer.fall_off_term): u_wd carries pi (K_D + K_A),
// the term's part up to alpha = 90 deg; this correction per unit map weight pi K_A (<= 0) takes off the part
// past 90 deg: max(0, D(N) - g1(-N.V) D'(B) - (1/pi) sum_l (N.l)+ (-R.l)+ flux_l) - D(N), with D' the
// diffuse map without the extracted lights at B = normalize(N - R) and
// g1(c) = (2/(3 pi))((pi - beta) c + sin beta), beta = acos c. Compiled in when a paint has K_A > 0 and
// the horizon tables are on (GLRenderer._terms; "none" is the thesis's model without it).
uniform vec3 u_wa[2];
vec3 fall_off(vec3 n, vec3 r, float ndv, vec3 d_n) {
    vec3 a = -r;
    vec3 b = normalize(n - r);
#if DIFFUSE_SH
    vec3 d_b = sh_eval(b);
#else
    vec3 d_b = textureLod(u_diffuse, b, 0.0).rgb;
#endif
    vec3 f = d_n;
    for (int l = 0; l < N_LIGHTS; ++l) {
        d_b -= max(dot(b, u_light_dir[l]), 0.0) / PI * u_light_flux[l];
        f -= max(dot(n, u_light_dir[l]), 0.0) * max(dot(a, u_light_dir[l]), 0.0) / PI * u_light_flux[l];
    }
    float c = -ndv;
    float beta = acos(clamp(c, -1.0, 1.0));
    float g1 = 2.0 / (3.0 * PI) * ((PI - beta) * c + sin(beta));
    return max(f - g1 * max(d_b, vec3(0.0)), vec3(0.0)) - d_n;
}
#endif

//#include anisotropy.glsl

#if MESH
in vec3 v_pos;
in vec3 v_normal;
flat in float v_painted;
#endif

#if MESH
// The diffuse reflectance of a neutral part (the factor of its diffuse-map term in part_radiance).
float part_diffuse(float code, float ndv) {
    float m = 1.0 - ndv, m5 = m * m * m * m * m;
    if (abs(code - MAT_TYRE) < 0.5) return TYRE_ALBEDO + (0.04 + 0.96 * m5) * 0.25;
    if (abs(code - MAT_GLASS) < 0.5) return (1.0 - (0.04 + 0.96 * m5)) * GLASS_INTERIOR;
    if (abs(code - MAT_CHROME) < 0.5) return 0.0;
    return NEUTRAL_ALBEDO;
}

// A mesh part that is not the paint (station.render.meshes: material codes): NEUTRAL_ALBEDO grey, matte
// tyre, glass (Schlick F0 0.04 mirror over a dark interior) or chrome (F0 0.6 mirror), the mirrors read in
// the sharpest lobe map (bound to u_flake_sharp for meshes).
vec3 part_radiance(float code, vec3 n, vec3 v) {
    vec3 ne = u_rot * n;
#if DIFFUSE_SH
    vec3 d_n = sh_eval(ne);
#else
    vec3 d_n = textureLod(u_diffuse, ne, 0.0).rgb;
#endif
    float ndv = clamp(dot(n, v), 0.0, 1.0);
    float m = 1.0 - ndv, m5 = m * m * m * m * m;
    vec3 mirror = textureLod(u_flake_sharp, u_rot * (2.0 * dot(n, v) * n - v), 0.0).rgb;
    vec3 diffuse = part_diffuse(code, ndv) * d_n;
    if (abs(code - MAT_GLASS) < 0.5) return (0.04 + 0.96 * m5) * mirror + diffuse;
    if (abs(code - MAT_CHROME) < 0.5) return (0.6 + 0.4 * m5) * mirror;
    return diffuse;  // tyre, neutral grey
}
#endif

#if MESH && N_SHADOW > 0 && N_LIGHTS > 0
// What the lights' shadows take from a neutral part's diffuse share (part_diffuse): sum over the shadowed
// lights of (1 - V) (N.l)+ flux / pi times the part's diffuse reflectance.
vec3 part_shadow_loss(float code, vec3 n, vec3 v) {
    vec3 loss = vec3(0.0);
    for (int l = 0; l < N_LIGHTS; ++l) {
        vec3 lw = u_light_world[l];
        float nl = dot(n, lw);
        if (nl > 0.0 && has_shadow_map(l)) loss += (1.0 - light_shadow(l, v_pos, n, lw)) * nl / PI * u_light_flux[l];
    }
    return part_diffuse(code, clamp(dot(n, v), 0.0, 1.0)) * loss;
}
#endif

#if COMBINED
#define N_LOOP N_WIDE
#else
#define N_LOOP N_LOBES
#endif
// The smooth terms of a paint (thesis eq. 2.5.3 over the wide lobes, all lobes without COMBINED, and the exact
// lights taken out of them): radiance += s g_sum + dd_sum, s the coat's factor on the gloss terms. They vary
// slowly over a surface: SMOOTH_OUT draws them at a coarser rate, SMOOTH_IN reads them back (GLRenderer).
// *lost*: what each shadowed light's map says the point has lost of it (main).
void smooth_terms(vec3 n, vec3 r, float ndv, int paint, vec2 lost, out vec3 g_sum, out vec3 dd_sum) {
    g_sum = vec3(0.0);
    dd_sum = vec3(0.0);
    // The paint's weights are selected per lobe (a select; indexing by the paint would gather).
    for (int i = 0; i < N_LOOP; ++i) {
        float wg = paint == 0 ? u_wg[i] : u_wg[N_LOBES + i];
        vec3 wdd = paint == 0 ? u_wdd[i] : u_wdd[N_LOBES + i];
        bool gloss = ((WIDE_GLOSS_MASK >> i) & 1) != 0;  // constant: no lookup for a zero gloss weight
        // h only for a gloss weight: g from the pair row when that row is read anyway, else wide_g (its
        // polynomial, or its row of g alone: one lookup for four such lobes)
        bool pair_read = (((WIDE_GLOSS_MASK >> (i - i % 2)) & 3) != 0);
        vec2 gh = pair_read ? horizon(i, ndv) : vec2(wide_g(i, ndv), 0.0);
#if BENT_DD
        // directionally diffuse lookup of a wide lobe at B = normalize(E R + COSINE_SG N)
        // (numpy_renderer.dd_direction, station.render.lobes.bent_direction)
        bool bent = LOBE_E[i] < WIDE_EXPONENT;
#else
        bool bent = false;
#endif
        vec3 c_r = (gloss || !bent) ? textureLod(u_lobes[i], r, 0.0).rgb : vec3(0.0);
        vec3 c_dd = bent ? textureLod(u_lobes[i], normalize(LOBE_E[i] * r + COSINE_SG * n), 0.0).rgb : c_r;
        if (gloss) g_sum += gh.y * wg * c_r;
        dd_sum += gh.x * wdd * c_dd;
    }
#if N_LIGHTS > 0
    // exact directional lights on the lobes they were taken out of (E < WIDE_EXPONENT):
    // wg 1[N.l>0] p(l) flux + wdd (N.l) p(l) flux, p = (E'+1)/(2 pi) max(R.l, 0)^E', the lobe smoothed
    // over the light's extent, E' = E / (1 + E s^2) (environment.spread_exponent); one log2 per light.
    for (int l = 0; l < N_LIGHTS; ++l) {
        float nl = dot(n, u_light_dir[l]);
        float lg = log2(max(dot(r, u_light_dir[l]), 1e-30));
        vec3 acc_g = vec3(0.0), acc_dd = vec3(0.0);
        for (int i = 0; i < N_LOOP; ++i) {
            if (LOBE_E[i] < WIDE_EXPONENT) {
                float wg = paint == 0 ? u_wg[i] : u_wg[N_LOBES + i];
                vec3 wdd = paint == 0 ? u_wdd[i] : u_wdd[N_LOBES + i];
                float e = LOBE_E[i] / (1.0 + LOBE_E[i] * u_light_spread[l]);
                float p = (e + 1.0) / (2.0 * PI) * exp2(e * lg);
                if (((WIDE_GLOSS_MASK >> i) & 1) != 0) acc_g += vec3(wg * p);
                acc_dd += nl * wdd * p;
            }
        }
#if N_SHADOW > 0
        // the light's direct part (its exact terms and its share of the diffuse map) times its visibility
        // at the world point shaded: the mesh's fragment, or the ray-cast shape's hit
        if (nl > 0.0 && has_shadow_map(l)) {
            float vis = 1.0 - (l == SHADOW_L0 ? lost.x : lost.y);
            // the light's share of the diffuse maps: pi K_A (u_wd - u_wk) of D; with a coat pi K_D (u_wk)
            // of D_coat, where it enters weighted by the coat's entry weight t(N.l) (ClearCoat.entry_scale)
            vec3 w_lit = paint == 0 ? u_wd[0] : u_wd[1];
#if HAS_COAT
            w_lit += (paint == 0 ? u_wk[0] : u_wk[1]) * (coat_entry_weight(nl, u_coat_n, u_coat_t) - 1.0);
#endif
            acc_g *= vis;
            acc_dd = vis * acc_dd - (1.0 - vis) * nl / PI * w_lit;
        }
#endif
        if (nl > 0.0) {
            g_sum += acc_g * u_light_flux[l];
            dd_sum += acc_dd * u_light_flux[l];
        }
    }
#endif
}

#if BAKE_GROUND
// One texel of the ground map: the disc's square [-1, 1]^2 (times the radius, about u_ground_c).
void main() {
    vec2 q = 2.0 * gl_FragCoord.xy / u_size - 1.0;
    vec3 p = vec3(u_ground_c.x + q.x * u_ground_radius, u_ground_y, u_ground_c.y + q.y * u_ground_radius);
#if SHADOW_PROBE
    f_color = vec4(shadow_probe(p, vec3(0.0, 1.0, 0.0)), 1.0);
#else
    f_color = vec4(ground_radiance(p), 1.0);
#endif
}
#else
void main() {
    float t;
    vec3 n;
    int paint;
    vec3 rgb = u_background;
#if MESH
    vec3 d = normalize(v_pos - u_eye);
    t = length(v_pos - u_eye);
    n = normalize(v_normal);
    if (dot(n, d) > 0.0) n = -n;  // shade the side facing the camera
#if MESH_PARTS == 1
    paint = v_pos.x < 0.0 ? 0 : 1;
#elif MESH_PARTS == 2
    paint = -1;
#else
    paint = abs(v_painted - MAT_PAINT) < 0.5 ? (v_pos.x < 0.0 ? 0 : 1) : -1;
#endif
    bool hit_any = true;
#else
    vec2 ndc = 2.0 * gl_FragCoord.xy / u_size - 1.0;
    vec3 d = normalize(u_forward + ndc.x * u_tan_half_fov * u_aspect * u_right + ndc.y * u_tan_half_fov * u_up);
#if NO_SHAPE
    bool hit_any = false;
#else
    bool hit_any = hit(u_eye, d, t, n, paint);
#if INSIDE_SHAPE
    hit_any = true;  // drawn inside the shape's silhouette only (station.render.footprint): no background
#endif
#endif
#endif
#if MESH && MESH_PARTS != 1
    if (hit_any && paint < 0) {
        rgb = part_radiance(v_painted, n, -d);
#if N_SHADOW > 0 && N_LIGHTS > 0
        rgb -= part_shadow_loss(v_painted, n, -d);
#endif
    }
#if MESH_PARTS == 0
    else
#endif
#endif
#if !(MESH && MESH_PARTS == 2)
    if (hit_any) {
        vec3 v = -d;
        float ndv = clamp(dot(n, v), 0.0, 1.0);
        vec3 n_world = n;  // the shadows' normal, before the turn into the environment's frame
#if HAS_STAGE
        vec3 r = u_rot * (2.0 * dot(n, v) * n - v);  // lookups in the environment's frame
        n = u_rot * n;
#else
        vec3 r = 2.0 * dot(n, v) * n - v;
#endif
#if HAS_COAT
        // The whole sum is scaled by the coat's transmission 1 - F at the end, so the gloss terms carry
        // F/(u_coat_ref (1 - F)) here: radiance = (1 - F) base + F/u_coat_ref gloss.
        float coat_f = coat_fresnel(ndv);
        float coat_t = max(1.0 - coat_f, 1e-4);
        float s = coat_f / (u_coat_ref * coat_t);
#else
        float s = 1.0;
#endif
        // What each shadowed light's map says the point has lost of it, 1 - V (all where the surface faces away
        // from the light): its exact terms and diffuse share below, its share of the narrow lobes and glints.
        vec2 lost = vec2(0.0);
#if N_SHADOW > 0
#if MESH
        vec3 p_shadow = v_pos;
#else
        vec3 p_shadow = u_eye + t * d;
#endif
        vec3 l_0 = u_light_world[SHADOW_L0];
        lost.x = 1.0 - (dot(n_world, l_0) > 0.0 ? light_shadow(SHADOW_L0, p_shadow, n_world, l_0) : 0.0);
#if N_SHADOW > 1
        vec3 l_1 = u_light_world[SHADOW_L1];
        lost.y = 1.0 - (dot(n_world, l_1) > 0.0 ? light_shadow(SHADOW_L1, p_shadow, n_world, l_1) : 0.0);
#endif
#endif
#if SMOOTH_OUT
        {
            vec3 g_sum, dd_sum;
            smooth_terms(n, r, ndv, paint, lost, g_sum, dd_sum);
            f_color = vec4(g_sum, 1.0);
            f_dd = vec4(dd_sum, 1.0);
            return;
        }
#endif
#if DIFFUSE_ATLAS
        // wd D + wk (D_coat - D) pre-mixed per paint: one lookup (combine_diffuse.frag.glsl)
        rgb = textureLod(u_diffuse_base, atlas_uv_of(n, paint, DIFFUSE_FACE), 0.0).rgb;
#else
#if DIFFUSE_SH
        vec3 d_n = sh_eval(n);
#else
        vec3 d_n = textureLod(u_diffuse, n, 0.0).rgb;
#endif
        rgb = (paint == 0 ? u_wd[0] : u_wd[1]) * d_n;
#if HAS_COAT
#if DIFFUSE_SH
        vec3 d_coat = sh_eval_with(u_sh_coat, n);
#else
        vec3 d_coat = textureLod(u_diffuse_coat, n, 0.0).rgb;
#endif
        rgb += (paint == 0 ? u_wk[0] : u_wk[1]) * (d_coat - d_n);  // pi K_D through the coat
#endif
#endif
#if HAS_FALL_OFF
        rgb += (paint == 0 ? u_wa[0] : u_wa[1]) * fall_off(n, r, ndv, d_n);
#endif
#if COMBINED
        {
            vec2 uv = atlas_uv(r, paint);  // one pair of lookups for either paint (no branch on the paint)
            vec3 narrow = s * textureLod(u_gloss, uv, 0.0).rgb;
#if NARROW_DD
            narrow += ndv * textureLod(u_dd, uv, 0.0).rgb;
#endif
#if N_SHADOW > 0 && SHADOWED_MAPS
            // in a light's shadow the narrow lobes without that light (station/render/gl_light_maps.py); the
            // lights written out (a loop over the sampler arrays cost 4 % more on llvmpipe), skipped where
            // every pixel of the block sees them
            if (lost.x + lost.y > 0.0) {
                narrow *= 1.0 - lost.x - lost.y;
                narrow += lost.x * s * textureLod(u_shadowed_gloss[0], uv, 0.0).rgb;
#if NARROW_DD
                narrow += lost.x * ndv * textureLod(u_shadowed_dd[0], uv, 0.0).rgb;
#endif
#if N_SHADOW > 1
                narrow += lost.y * s * textureLod(u_shadowed_gloss[1], uv, 0.0).rgb;
#if NARROW_DD
                narrow += lost.y * ndv * textureLod(u_shadowed_dd[1], uv, 0.0).rgb;
#endif
#endif
            }
#endif
            rgb += narrow;
        }
#endif
#if SMOOTH_IN
        // the smooth terms from the coarse pass (SMOOTH_OUT), bilinear at this pixel
        {
            vec2 cuv = gl_FragCoord.xy / u_size;
            rgb += s * textureLod(u_smooth_g, cuv, 0.0).rgb + textureLod(u_smooth_dd, cuv, 0.0).rgb;
        }
#else
        {
            vec3 g_sum, dd_sum;
            smooth_terms(n, r, ndv, paint, lost, g_sum, dd_sum);
            rgb += s * g_sum + dd_sum;
        }
#endif
#if HAS_FLAKES
        vec3 sparkle = flake_sparkle(u_eye + t * d, t, ndv, n, u_rot * v, r, paint, lost);
#else
        vec3 sparkle = vec3(0.0);
#endif
#if HAS_ANISO
#if HAS_STAGE
        rgb += s * aniso_gloss(n, u_rot * v, u_rot * u_aniso_hint, paint);
#else
        rgb += s * aniso_gloss(n, v, u_aniso_hint, paint);
#endif
#endif
#if HAS_COAT
        rgb *= coat_t;  // base and flakes lie under the coat (the gloss terms were divided by coat_t above)
        sparkle *= coat_t;
#endif
        rgb += max(sparkle, -u_flake_reflectance * rgb);  // a cell's flakes never reflect less than nothing
    } else {
#if HAS_STAGE && !SMOOTH_OUT
        rgb = stage_background(u_eye, d);
#endif
    }
#endif
#if SMOOTH_OUT
    f_color = vec4(0.0);
    f_dd = vec4(0.0);
#elif OUTPUT_LINEAR && SHADOW_PROBE && MESH
    vec3 nw = normalize(v_normal);
    if (dot(nw, v_pos - u_eye) > 0.0) nw = -nw;
    rgb = shadow_probe(v_pos, nw);
    f_color = vec4(rgb.x, v_pos);  // the strongest light's visibility at world point v_pos
#elif OUTPUT_LINEAR && SHADOW_PROBE && !NO_SHAPE
    // a ray-cast shape: the strongest light's visibility at its hit and the hit's world point (-1: a miss)
    f_color = vec4(-1.0, 0.0, 0.0, 0.0);
    float t_probe;
    vec3 n_probe;
    int paint_probe;
    if (hit(u_eye, d, t_probe, n_probe, paint_probe)) {
        vec3 p_probe = u_eye + t_probe * d;
        f_color = vec4(shadow_probe(p_probe, n_probe).x, p_probe);
    }
#elif OUTPUT_LINEAR
    f_color = vec4(rgb, 1.0);
#else
    f_color = vec4(display(rgb), 1.0);
#endif
}
#endif
