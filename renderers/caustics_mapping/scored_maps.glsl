// Pass 3c, the end of the receivers' maps where the triangles went to a finer atlas
// (caustic_lookup = "receivers"): the maps scored, each coarse texel plus the mean
// of the u_factor x u_factor finer texels over it. A triangle's finer texel values
// are its integrals over each of them, so their mean is its integral over the
// coarser texel. Input: the two RGBA32F atlases (rgb W/m^2, a splat weight), the
// finer one u_factor times as many texels per side; output: the coarse atlas's size.
#include "common.glsl"

uniform sampler2D u_coarse;
uniform sampler2D u_fine;
uniform int u_factor;

#include "fullscreen.glsl"

#if defined FRAGMENT_SHADER
out vec4 out_color;
void main() {
    ivec2 t = ivec2(gl_FragCoord.xy);
    vec4 sum = vec4(0.0);
    for (int dy = 0; dy < u_factor; ++dy)
        for (int dx = 0; dx < u_factor; ++dx)
            sum += texelFetch(u_fine, u_factor * t + ivec2(dx, dy), 0);
    out_color = texelFetch(u_coarse, t, 0) + sum / float(u_factor * u_factor);
}
#endif
