// The clear coat's Fresnel reflectance and entry weight, the GLSL twins of station.model.fresnel
// (fresnel_dielectric, ClearCoat.entry_scale); render.frag.glsl and prefilter_brute.frag.glsl include them
// and tests/render/test_coat_shadow.py checks them against the Python at a grid of cosines.

// Exact unpolarised Fresnel reflectance of a dielectric of index n from air at incidence cosine c
// (clamped to [0, 1]): ((n - 1)/(n + 1))^2 head-on, 1 at grazing, never more.
float dielectric_fresnel(float c, float n) {
    float ci = clamp(c, 0.0, 1.0);
    float ct = sqrt(max(1.0 - (1.0 - ci * ci) / (n * n), 0.0));
    float rs = (ci - n * ct) / (ci + n * ct);
    float rp = (n * ci - ct) / (n * ci + ct);
    return 0.5 * (rs * rs + rp * rp);
}

// The weight (1 - F(c; n)) / t of light arriving at N.l = c on the diffuse base under the coat, t = 1 - F_dr,ext
// (ClearCoat.entry_scale, ClearCoat.diffuse_transmission).
float coat_entry_weight(float c, float n, float t) {
    return (1.0 - dielectric_fresnel(c, n)) / t;
}
