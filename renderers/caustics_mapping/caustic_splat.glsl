// Pass 3b: splat the trace records into the caustic-map atlas with additive
// blending (paper Sections 3.3 and 3.6), with the kernels of splat_kernels.glsl.
//
// Output (RGBA32F map atlas, u_size texels per face): rgb caustic irradiance E
// (W/m^2) on the receiver seen in that texel, a = kernel weight. A Gaussian's
// discrete weights are normalised to sum to one over the texels it covers and
// divided by the receiver area of one texel at the hit; a triangle holds its flux
// over its area on the receiver. So a texel holds flux / area: irradiance.
//
// Two programs: the Gaussians (splat_gaussians.glsl: points, footprint, and the
// triangles' leftovers; one vertex per record) and, with TRIANGLES defined, the
// triangles (splat_triangles.glsl: one vertex per grid quad, expanded by the
// geometry shader).
#include "common.glsl"

uniform int u_size;          // caustic-map texels per face side
uniform int u_face;          // the face being drawn (viewport and scissor set to it)

#include "splat_kernels.glsl"

#if defined VERTEX_SHADER || defined GEOMETRY_SHADER || defined COMPUTE_SHADER
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
#if defined GEOMETRY_SHADER || defined COMPUTE_SHADER
// Area on the receiver of a triangle of hits, measured across the receiver's normal.
float triangle_area(vec2 a, vec2 b, vec2 c, vec3 pa, vec3 pb, vec3 pc, vec3 n) {
    return 0.5 * abs(dot(cross(pb - pa, pc - pa), n));
}
#endif
#include "splat_triangles.glsl"
#else  // Gaussians
#if defined COMPUTE_SHADER
// points: u_sigma texels in every direction; footprint: the grid's hit differences.
mat2 gaussian_covariance(int view, int tx, int ty, vec3 hit, vec3 normal, inout vec2 c) {
    return u_splat_mode == SPLAT_POINTS ? mat2(u_sigma * u_sigma)
        : footprint_covariance(view, tx, ty, c, u_sigma);
}

void target_bounds(out vec2 lo, out vec2 hi) {        // face u_face of the atlas
    float slot = float(u_map_slot[u_face] * u_size);
    lo = vec2(slot, 0.0);
    hi = vec2(slot + float(u_size), float(u_size));
}

// A = the receiver area (m^2) one caustic-map texel covers at the hit.
vec3 gaussian_value(vec3 flux, float norm, vec3 hit, vec3 normal) {
    int face;
    vec2 ndc;
    ivec2 texel;
    map_locate(hit, u_size, face, ndc, texel);
    float area = map_texel_area(hit, normal, ndc, u_size);
    return flux / (norm * area);
}
#endif
#include "splat_gaussians.glsl"
#endif
