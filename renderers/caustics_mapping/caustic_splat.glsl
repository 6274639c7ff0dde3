// Pass 3b: splat the trace records into the caustic-map atlas as Gaussian point
// sprites with additive blending (paper Sections 3.3 and 3.6).
//
// Output (RGBA32F map atlas, u_size texels per face): rgb caustic irradiance E
// (W/m^2) on the receiver seen in that texel, a = splat weight (sums to the number
// of splats). Each splat's discrete Gaussian weights are normalised to sum to one
// over the texels it covers, and divided by the receiver area of one texel at the
// hit, so a texel holds flux / area: irradiance.
#include "common.glsl"

uniform int u_size;        // caustic-map texels per face side
uniform int u_face;        // the face being drawn (viewport and scissor set to it)
uniform float u_sigma;     // Gaussian standard deviation (texels)
uniform float u_cut;       // cut-off radius (sigmas)

#if defined VERTEX_SHADER
in vec4 in_hit;      // xyz P (m), w status
in vec4 in_flux;     // rgb flux (W), w receiver index
in vec4 in_normal;   // receiver normal at P
flat out vec3 v_value;
flat out vec2 v_center;
void main() {
    v_value = vec3(0.0);
    v_center = vec2(0.0);
    gl_PointSize = 1.0;
    gl_Position = vec4(2.0, 2.0, 2.0, 1.0);              // culled unless set below
    if (int(in_hit.w + 0.5) != STATUS_HIT) return;
    int face;
    vec2 ndc;
    ivec2 texel;
    if (!map_locate(in_hit.xyz, u_size, face, ndc, texel) || face != u_face) return;
    vec2 c = (ndc * 0.5 + 0.5) * float(u_size);          // face pixels
    float norm = splat_norm(c, vec2(u_sigma), u_cut, vec2(0.0), vec2(float(u_size)));
    if (!(norm > 0.0)) return;
    float area = map_texel_area(in_hit.xyz, in_normal.xyz, ndc, u_size);
    v_value = in_flux.rgb / (norm * area);
    v_center = c + vec2(float(u_map_slot[face] * u_size), 0.0);  // atlas pixels
    // The sprite covers the pixel centres within ceil(cut * sigma) of c (a square of
    // half-width ceil(cut * sigma) + 0.5): every texel the cut-off disc reaches.
    gl_PointSize = 2.0 * ceil(u_cut * u_sigma) + 1.0;
    gl_Position = vec4(ndc, 0.0, 1.0);
}
#elif defined FRAGMENT_SHADER
flat in vec3 v_value;
flat in vec2 v_center;
out vec4 out_irradiance;
void main() {
    float w = splat_weight(gl_FragCoord.xy, v_center, vec2(u_sigma), u_cut);
    if (w < 0.0) discard;
    out_irradiance = vec4(v_value * w, w);
}
#endif
