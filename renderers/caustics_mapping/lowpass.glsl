// Optional low-pass filter of the caustic map (paper Section 3.6): a 3x3 binomial
// kernel [1 2 1]^T [1 2 1] / 16, applied within each slot of the atlas (texel
// coordinates are clamped to the slot, so slots do not bleed into each other).
// Input and output: RGBA32F atlas (rgb W/m^2, a splat weight) of u_size slots side
// by side: the caustic map's faces, or the receivers' (u, v) maps.
#include "common.glsl"

uniform sampler2D u_source;
uniform ivec2 u_size;              // W, H texels of one slot

#include "fullscreen.glsl"

#if defined FRAGMENT_SHADER
out vec4 out_color;
void main() {
    ivec2 t = ivec2(gl_FragCoord.xy);
    int slot = t.x / u_size.x;
    ivec2 lo = ivec2(slot * u_size.x, 0);
    ivec2 hi = lo + u_size - 1;
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
