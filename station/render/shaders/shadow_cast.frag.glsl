#version 430
// Depth pass of a ray-cast shape in an orthographic view (station/render/gl_shadows.py): per texel the ray
// from the view's near plane along its depth axis u_dir (world, unit) is cast at the analytic shape
// (shaders/shapes.glsl, the frame's own hit()), and its distance t to the first hit written as the map's
// depth t / u_depth (u_depth: world depth over 0 ... 1); a miss writes nothing. u_inv takes the texel's
// (u, v, 0) back to the world. u_from_below (1): the view from below of the height maps, where the
// cylinder, open below, is taken as the solid column it bounds (its bottom at its base y = -1).
uniform mat4 u_inv;
uniform vec3 u_dir;
uniform vec2 u_size;
uniform vec2 u_origin;  // the tile's first texel in an atlas (station.render.gl_shadows: a wide light's disc)
uniform float u_depth;
uniform int u_from_below;
//#include shapes.glsl

void main() {
    vec2 uv = (gl_FragCoord.xy - u_origin) / u_size;
    vec3 o = (u_inv * vec4(uv, 0.0, 1.0)).xyz;
    float t;
    vec3 n;
    int paint;
    if (!hit(o, u_dir, t, n, paint)) discard;
#if SHAPE == 1
    if (u_from_below == 1) t = (-1.0 - o.y) / u_dir.y;
#endif
    gl_FragDepth = clamp(t / u_depth, 0.0, 1.0);
}
