#version 330
// Shows a finished 8-bit sRGB frame (the core's NumPy paint edit, station/render/basis_images.py
// BasisImages.edit_rgba) texel for texel; row 0 of the frame is the top row.
uniform sampler2D u_frame;
uniform vec2 u_viewport;
uniform ivec2 u_size;
out vec4 f_color;

void main() {
    ivec2 px = ivec2(gl_FragCoord.x * float(u_size.x) / u_viewport.x,
                     float(u_size.y) - gl_FragCoord.y * float(u_size.y) / u_viewport.y);
    px = clamp(px, ivec2(0), u_size - 1);
    f_color = vec4(texelFetch(u_frame, px, 0).rgb, 1.0);
}
