// Display transform, the same formulas as station/render/tonemap.py (the OETF's power segment as its
// polynomial, SRGB_POLY).
// CURVE (compiled in per frame's curve): 0 = ACES fit (Narkowicz 2015), 1 = Reinhard x/(1+x), 2 = clip.
#ifndef CURVE
#define CURVE 0
#endif
uniform float u_exposure;  // 2^EV

vec3 tone_curve(vec3 x) {
    x = max(x, vec3(0.0));
#if CURVE == 0
    vec3 y = x * (2.51 * x + 0.03) / (x * (2.43 * x + 0.59) + 0.14);
#elif CURVE == 1
    vec3 y = x / (1.0 + x);
#else
    vec3 y = x;
#endif
    return clamp(y, 0.0, 1.0);
}

// The sRGB OETF; its power segment without pow (station.render.tonemap.SRGB_POLY, compiled in):
// x^(1/2.4) = sqrt(x) t^(-4/3), t = x^(1/16), t^(-4/3) a polynomial in u = SRGB_T_SCALE t + SRGB_T_OFFSET.
const float SRGB_C[7] = float[7](SRGB_POLY);
vec3 srgb_encode(vec3 x) {
    x = clamp(x, 0.0, 1.0);
    vec3 s = sqrt(x);
    vec3 u = SRGB_T_SCALE * sqrt(sqrt(sqrt(s))) + SRGB_T_OFFSET;
    vec3 p = vec3(SRGB_C[6]);
    for (int k = 5; k >= 0; --k) p = p * u + SRGB_C[k];
    return mix(1.055 * s * p - 0.055, 12.92 * x, lessThanEqual(x, vec3(0.0031308)));
}

vec3 display(vec3 linear_rgb) {
    return srgb_encode(tone_curve(linear_rgb * u_exposure));
}
