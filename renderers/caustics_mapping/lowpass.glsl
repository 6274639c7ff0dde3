// Optional low-pass filter of the caustic map (paper Section 3.6): a 3x3 binomial
// kernel [1 2 1]^T [1 2 1] / 16, applied within each face of the atlas (texel
// coordinates are clamped to the face, so faces do not bleed into each other).
// Input and output: RGBA32F caustic-map atlas (rgb W/m^2, a splat weight).
#include "common.glsl"

uniform sampler2D u_source;
uniform int u_size;

#if defined VERTEX_SHADER
void main() {
    // A full-screen triangle from gl_VertexID.
    vec2 p = vec2(float((gl_VertexID << 1) & 2), float(gl_VertexID & 2));
    gl_Position = vec4(p * 2.0 - 1.0, 0.0, 1.0);
}
#elif defined FRAGMENT_SHADER
out vec4 out_color;
void main() {
    ivec2 t = ivec2(gl_FragCoord.xy);
    int face = t.x / u_size;
    ivec2 lo = ivec2(face * u_size, 0);
    ivec2 hi = ivec2(face * u_size + u_size - 1, u_size - 1);
    vec4 sum = vec4(0.0);
    for (int dy = -1; dy <= 1; ++dy) {
        for (int dx = -1; dx <= 1; ++dx) {
            float w = float((2 - abs(dx)) * (2 - abs(dy)));
            sum += w * texelFetch(u_source, clamp(t + ivec2(dx, dy), lo, hi), 0);
        }
    }
    out_color = sum / 16.0;
}
#endif
