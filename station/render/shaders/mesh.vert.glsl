#version 430
// Rasterised meshes (station/render/meshes.py) with the ray generator's pinhole camera
// (station/render/camera.py): clip = (x_cam / (tan(fov/2) aspect), y_cam / tan(fov/2), depth, z_cam),
// depth mapping near 0.05 ... far 100. World position, normal and paint flag go to render.frag.glsl (MESH).
in vec3 in_pos;
in vec3 in_normal;
in float in_painted;
uniform vec3 u_eye, u_forward, u_right, u_up;
uniform float u_tan_half_fov, u_aspect;
out vec3 v_pos;
out vec3 v_normal;
flat out float v_painted;  // a material code, one per triangle
const float NEAR = 0.05, FAR = 100.0;
// The same depth in the depth pre-pass and the shading pass (station/render/gl_passes.py), which tests <=.
invariant gl_Position;

void main() {
    vec3 rel = in_pos - u_eye;
    float z = dot(rel, u_forward);
    gl_Position = vec4(dot(rel, u_right) / (u_tan_half_fov * u_aspect), dot(rel, u_up) / u_tan_half_fov,
                       ((FAR + NEAR) * z - 2.0 * FAR * NEAR) / (FAR - NEAR), z);
    v_pos = in_pos;
    v_normal = in_normal;
    v_painted = in_painted;
}
