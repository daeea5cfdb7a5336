#version 430
// Supersampling resolve: each output pixel is the box mean of its FACTOR x FACTOR block of the frame
// rendered at FACTOR times the size (an unweighted mean: the pixel's area coverage of every edge).
uniform sampler2D u_src;
out vec4 f_color;
void main() {
    ivec2 base = ivec2(gl_FragCoord.xy) * FACTOR;
    vec4 sum = vec4(0.0);
    for (int j = 0; j < FACTOR; ++j) {
        for (int i = 0; i < FACTOR; ++i) {
            sum += texelFetch(u_src, base + ivec2(i, j), 0);
        }
    }
    f_color = sum / float(FACTOR * FACTOR);
}
