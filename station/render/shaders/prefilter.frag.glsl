#version 430
// Normalised Phong-lobe prefiltering by deterministic quadrature on a tangent-plane grid.
// Output: six cube faces stacked vertically in one (S, 6S) float target; texel (x, y) of face
// f = y / S. Around each texel direction R, a G x G grid over [-u_max, u_max]^2 of the tangent
// plane (u_max = tan theta_max, theta_max where cos^n falls to 1e-3) gives directions
// w = normalize(R + u T + v B), each weighted by the lobe (n+1)/(2pi) cos^n times the cell's
// solid angle h^2 cos^3; the source cube is read at the mip level whose texel matches the grid step
// h, so every sample is a box average over its cell. The weighted sum is divided by the sum of
// weights (exact for a constant environment; removes the truncated tail's deficit).
//#include cubeface.glsl
uniform samplerCube u_src;
uniform float u_exponent;
uniform int u_grid;
uniform int u_size;
uniform float u_umax;
uniform float u_lod;
out vec4 f_color;

void main() {
    ivec2 p = ivec2(gl_FragCoord.xy);
    int face = p.y / u_size;
    int row = p.y - face * u_size;
    float a = 2.0 * (float(p.x) + 0.5) / float(u_size) - 1.0;
    float b = 2.0 * (float(row) + 0.5) / float(u_size) - 1.0;
    vec3 R = normalize(cube_face_dir(face, a, b));
    vec3 up = abs(R.y) < 0.999 ? vec3(0.0, 1.0, 0.0) : vec3(1.0, 0.0, 0.0);
    vec3 T = normalize(cross(up, R));
    vec3 B = cross(R, T);
    float h = 2.0 * u_umax / float(u_grid);
    vec3 sum = vec3(0.0);
    float wsum = 0.0;
    for (int j = 0; j < u_grid; ++j) {
        float v = -u_umax + (float(j) + 0.5) * h;
        for (int i = 0; i < u_grid; ++i) {
            float u = -u_umax + (float(i) + 0.5) * h;
            float c = inversesqrt(1.0 + u * u + v * v);
            float w = pow(c, u_exponent + 3.0);
            sum += w * textureLod(u_src, R + u * T + v * B, u_lod).rgb;
            wsum += w;
        }
    }
    f_color = vec4(sum / wsum, 1.0);
}
