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
#if defined VERTEX_SHADER
flat out int v_quad;
void main() {
    v_quad = gl_VertexID;
    gl_Position = vec4(0.0);
}
#elif defined GEOMETRY_SHADER
layout(points) in;
layout(triangle_strip, max_vertices = 8) out;
flat in int v_quad[];
flat out vec2 g_a;
flat out vec2 g_b;
flat out vec2 g_c;
flat out vec2 g_lo;
flat out vec3 g_value;

void emit_triangle(vec2 a, vec2 b, vec2 c, vec3 pa, vec3 pb, vec3 pc, vec3 n, vec3 flux) {
    float area = 0.5 * abs(dot(cross(pb - pa, pc - pa), n));   // m^2 on the receiver
    if (!(area > 0.0)) return;
    vec2 lo = floor(min(min(a, b), c));
    vec2 hi = ceil(max(max(a, b), c));
    hi = max(hi, lo + 1.0);
    g_a = a - lo;
    g_b = b - lo;
    g_c = c - lo;
    g_lo = lo;
    g_value = flux / area;                                  // W/m^2
    vec2 corner[4] = vec2[4](lo, vec2(hi.x, lo.y), vec2(lo.x, hi.y), hi);
    for (int k = 0; k < 4; ++k) {
        gl_Position = target_position(corner[k]);
        EmitVertex();
    }
    EndPrimitive();
}

void main() {
    int per_view = (u_grid - 1) * (u_grid - 1);
    int view = v_quad[0] / per_view;
    int local = v_quad[0] - view * per_view;
    int qx = local % (u_grid - 1), qy = local / (u_grid - 1);
    vec2 c[4];
    if (!quad_drawn(view, qx, qy, c)) return;
    int i0 = grid_record(view, qx, qy), i1 = grid_record(view, qx + 1, qy);
    int i2 = grid_record(view, qx + 1, qy + 1), i3 = grid_record(view, qx, qy + 1);
    vec3 flux = 0.25 * (splat_records[i0 * 5 + 3].rgb + splat_records[i1 * 5 + 3].rgb
                        + splat_records[i2 * 5 + 3].rgb + splat_records[i3 * 5 + 3].rgb);
    vec3 p0 = splat_records[i0 * 5 + 2].xyz, p1 = splat_records[i1 * 5 + 2].xyz;
    vec3 p2 = splat_records[i2 * 5 + 2].xyz, p3 = splat_records[i3 * 5 + 2].xyz;
    // The receiver's normal (mean of the corners'): a normal taken from the hits
    // themselves would tilt with their rounding on tiny triangles and, since only
    // |cos| <= 1 enters, always inflate the area (lost 4e-4 of the flux).
    vec3 n = splat_records[i0 * 5 + 4].xyz + splat_records[i1 * 5 + 4].xyz
        + splat_records[i2 * 5 + 4].xyz + splat_records[i3 * 5 + 4].xyz;
    n = dot(n, n) > 0.0 ? normalize(n) : vec3(0.0, 0.0, 1.0);
    emit_triangle(c[0], c[1], c[2], p0, p1, p2, n, 0.5 * flux);
    emit_triangle(c[0], c[2], c[3], p0, p2, p3, n, 0.5 * flux);
}
#elif defined FRAGMENT_SHADER
flat in vec2 g_a;
flat in vec2 g_b;
flat in vec2 g_c;
flat in vec2 g_lo;
flat in vec3 g_value;
out vec4 out_irradiance;
void main() {
    vec2 rel = floor(gl_FragCoord.xy) - g_lo;
    float covered = pixel_coverage(g_a - rel, g_b - rel, g_c - rel);
    if (covered <= 0.0) discard;
    out_irradiance = vec4(g_value * covered, covered);
}
#endif

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
