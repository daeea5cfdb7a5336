#version 430
// One triangle covering the viewport; v_uv in [0, 1]² over the visible part. It lies on the far plane
// (depth 1): a mesh's stage pass is drawn only where the mesh's depth pre-pass left the depth at 1
// (station/render/gl_passes.py); the other passes draw without a depth test.
out vec2 v_uv;
void main() {
    vec2 p = vec2(float((gl_VertexID << 1) & 2), float(gl_VertexID & 2));
    v_uv = p;
    gl_Position = vec4(p * 2.0 - 1.0, 1.0, 1.0);
}
