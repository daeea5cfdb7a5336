#version 430
// Depth pass of a mesh in an orthographic view (station/render/gl_shadows.py): a light's shadow map, or
// the height maps from above and below; u_clip (column-major) takes a world point to GL clip space.
in vec3 in_pos;
uniform mat4 u_clip;
void main() {
    gl_Position = u_clip * vec4(in_pos, 1.0);
}
