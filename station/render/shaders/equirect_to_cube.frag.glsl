#version 430
// Equirectangular -> cube faces stacked vertically in an (S, 6S) target, each texel the mean of
// SUB x SUB bilinear samples at half-texel spacing (with S = W/4 that is half-pixel spacing in the
// source: every source pixel gets its share, so small bright sources keep their energy).
//#include cubeface.glsl
uniform sampler2D u_equirect;
uniform int u_size;
out vec4 f_color;
const float PI = 3.14159265358979;
const int SUB = 2;

vec2 equirect_uv(vec3 d) {
    return vec2(atan(d.x, -d.z) / (2.0 * PI) + 0.5, acos(clamp(d.y, -1.0, 1.0)) / PI);
}

void main() {
    ivec2 p = ivec2(gl_FragCoord.xy);
    int face = p.y / u_size;
    int row = p.y - face * u_size;
    vec3 sum = vec3(0.0);
    for (int j = 0; j < SUB; ++j) {
        for (int i = 0; i < SUB; ++i) {
            float a = 2.0 * (float(p.x) + (float(i) + 0.5) / float(SUB)) / float(u_size) - 1.0;
            float b = 2.0 * (float(row) + (float(j) + 0.5) / float(SUB)) / float(u_size) - 1.0;
            sum += textureLod(u_equirect, equirect_uv(normalize(cube_face_dir(face, a, b))), 0.0).rgb;
        }
    }
    f_color = vec4(sum / float(SUB * SUB), 1.0);
}
