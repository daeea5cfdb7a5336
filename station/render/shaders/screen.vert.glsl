#version 430
// Triangles given in normalised device coordinates (station.render.footprint: the shape's screen polygon
// and the rest of the viewport); the fragment shader casts its ray from gl_FragCoord.
in vec2 in_ndc;
void main() {
    gl_Position = vec4(in_ndc, 0.0, 1.0);
}
