// Pass 3b: splat the trace records into the caustic-map atlas with additive
// blending (paper Sections 3.3 and 3.6), with the kernels of splat_kernels.glsl.
//
// Output (RGBA32F map atlas, u_size texels per face): rgb caustic irradiance E
// (W/m^2) on the receiver seen in that texel, a = kernel weight. A Gaussian's
// discrete weights are normalised to sum to one over the texels it covers and
// divided by the receiver area of one texel at the hit; a triangle holds its flux
// over its area on the receiver. So a texel holds flux / area: irradiance.
//
// Two programs: the Gaussians (points, footprint, and the triangles' leftovers;
// one vertex per record) and, with TRIANGLES defined, the triangles (one vertex per
// grid quad, expanded by the geometry shader).
#include "common.glsl"

uniform int u_size;          // caustic-map texels per face side
uniform int u_face;          // the face being drawn (viewport and scissor set to it)
uniform float u_sigma;       // points: Gaussian standard deviation (texels)
uniform float u_cut;         // Gaussian cut-off radius (sigmas)
uniform float u_max_radius;  // Gaussian sprite radius cap (texels)

#include "splat_kernels.glsl"

#if defined VERTEX_SHADER || defined GEOMETRY_SHADER
// The record's hit in atlas pixels, when it is splatted into face u_face.
bool to_target(int record, out vec2 pix) {
    pix = vec2(0.0);
    vec4 hit = splat_records[record * 5 + 2];
    if (!splatted(hit.w, splat_records[record * 5 + 3].w)) return false;
    int face;
    vec2 ndc;
    ivec2 texel;
    if (!map_locate(hit.xyz, u_size, face, ndc, texel) || face != u_face) return false;
    pix = (ndc * 0.5 + 0.5) * float(u_size) + vec2(float(u_map_slot[face] * u_size), 0.0);
    return true;
}

vec4 target_position(vec2 pix) {
    vec2 face_pix = pix - vec2(float(u_map_slot[u_face] * u_size), 0.0);
    return vec4(face_pix / float(u_size) * 2.0 - 1.0, 0.0, 1.0);
}
#endif

#if defined TRIANGLES
#if defined GEOMETRY_SHADER
// Area on the receiver of a triangle of hits, measured across the receiver's normal.
float triangle_area(vec2 a, vec2 b, vec2 c, vec3 pa, vec3 pb, vec3 pc, vec3 n) {
    return 0.5 * abs(dot(cross(pb - pa, pc - pa), n));
}
#endif
#include "splat_triangles.glsl"
#else  // Gaussians
#if defined VERTEX_SHADER
in vec4 in_hit;      // xyz P (m), w status
in vec4 in_flux;     // rgb flux (W), w receiver index
in vec4 in_normal;   // receiver normal at P
flat out vec3 v_value;
flat out vec2 v_center;
flat out mat2 v_inverse;
void main() {
    v_value = vec3(0.0);
    v_center = vec2(0.0);
    v_inverse = mat2(1.0);
    gl_PointSize = 1.0;
    gl_Position = vec4(2.0, 2.0, 2.0, 1.0);              // culled unless set below
    vec2 c;
    if (!to_target(gl_VertexID, c)) return;
    int per_view = u_grid * u_grid;
    int view = gl_VertexID / per_view;
    int local = gl_VertexID - view * per_view;
    int tx = local % u_grid, ty = local / u_grid;
    float share = gaussian_share(view, tx, ty);
    if (share <= 0.0) return;
    mat2 cov = u_splat_mode == SPLAT_POINTS ? mat2(u_sigma * u_sigma)
        : footprint_covariance(view, tx, ty, c, u_sigma);
    float radius = fit_radius(cov, u_cut, u_max_radius);
    mat2 inv = inverse(cov);
    float slot = float(u_map_slot[u_face] * u_size);
    float norm = gaussian_norm(c, inv, radius, u_cut, vec2(slot, 0.0),
                               vec2(slot + float(u_size), float(u_size)));
    if (!(norm > 0.0)) return;
    int face;
    vec2 ndc;
    ivec2 texel;
    map_locate(in_hit.xyz, u_size, face, ndc, texel);
    float area = map_texel_area(in_hit.xyz, in_normal.xyz, ndc, u_size);
    v_value = share * in_flux.rgb / (norm * area);
    v_center = c;
    v_inverse = inv;
    // The sprite covers the pixel centres within ceil(radius) of c: every texel the
    // cut-off ellipse reaches.
    gl_PointSize = 2.0 * ceil(radius) + 1.0;
    gl_Position = target_position(c);
}
#elif defined FRAGMENT_SHADER
flat in vec3 v_value;
flat in vec2 v_center;
flat in mat2 v_inverse;
out vec4 out_irradiance;
void main() {
    vec2 q = gl_FragCoord.xy - v_center;
    float e = dot(q, v_inverse * q);
    if (e > u_cut * u_cut) discard;
    float w = exp(-0.5 * e);
    out_irradiance = vec4(v_value * w, w);
}
#endif
#endif
