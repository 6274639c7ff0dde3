// The triangles program of a splat pass (splat_kernels.glsl, kernel `triangles`),
// included by caustic_splat.glsl and receiver_splat.glsl under TRIANGLES: one vertex
// per grid quad; the geometry shader turns a drawn quad into its two triangles
// (c0 c1 c2 and c0 c2 c3), emitted together as the quad's bounding box of whole
// pixels with the four corners (relative to the box) and each triangle's irradiance
// (W/m^2: half the quad's flux over the triangle's area on the receiver); the
// fragment shader weights each irradiance by the area of its pixel that triangle
// covers. One box per quad, not one per triangle: each triangle's box is nearly the
// quad's, so this rasterises half the pixels and sets up half the primitives (on
// llvmpipe, setting up the boxes' primitives was most of the pass). The including
// pass defines
//   vec4 target_position(vec2 pix)      target pixels -> clip position
//   float triangle_area(vec2 a, vec2 b, vec2 c, vec3 pa, vec3 pb, vec3 pc, vec3 n)
//                                        the triangle's area (m^2) on the receiver,
//                                        from its target pixels a, b, c, its hits
//                                        pa, pb, pc and the receiver normal n
#if defined VERTEX_SHADER
flat out int v_quad;
void main() {
    v_quad = gl_VertexID;
    gl_Position = vec4(0.0);
}
#elif defined GEOMETRY_SHADER
layout(points) in;
layout(triangle_strip, max_vertices = 4) out;
flat in int v_quad[];
flat out vec2 g_c0;
flat out vec2 g_c1;
flat out vec2 g_c2;
flat out vec2 g_c3;
flat out vec2 g_lo;
flat out vec4 g_first;          // rgb W/m^2 of triangle c0 c1 c2; a 1 if it is drawn
flat out vec4 g_second;         // the same of triangle c0 c2 c3

// Irradiance (W/m^2) of a triangle carrying `flux` (W), flux over its area on the
// receiver, and 1; zeros for a triangle of no area (it is not drawn).
vec4 triangle_value(vec2 a, vec2 b, vec2 c, vec3 pa, vec3 pb, vec3 pc, vec3 n, vec3 flux) {
    float area = triangle_area(a, b, c, pa, pb, pc, n);        // m^2 on the receiver
    return area > 0.0 ? vec4(flux / area, 1.0) : vec4(0.0);
}

void main() {
    int per_view = (u_grid - 1) * (u_grid - 1);
    int view = v_quad[0] / per_view;
    int local = v_quad[0] - view * per_view;
    int qx = local % (u_grid - 1), qy = local / (u_grid - 1);
    vec2 c[4];
    bool drawn = quad_drawn(view, qx, qy, c);
    quad_flags[v_quad[0]] = drawn ? 1 : 0;          // for the Gaussians drawn next
    if (!drawn) return;
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
    g_first = triangle_value(c[0], c[1], c[2], p0, p1, p2, n, 0.5 * flux);
    g_second = triangle_value(c[0], c[2], c[3], p0, p2, p3, n, 0.5 * flux);
    vec2 lo = floor(min(min(c[0], c[1]), min(c[2], c[3])));
    vec2 hi = ceil(max(max(c[0], c[1]), max(c[2], c[3])));
    hi = max(hi, lo + 1.0);
    g_c0 = c[0] - lo;
    g_c1 = c[1] - lo;
    g_c2 = c[2] - lo;
    g_c3 = c[3] - lo;
    g_lo = lo;
    vec2 corner[4] = vec2[4](lo, vec2(hi.x, lo.y), vec2(lo.x, hi.y), hi);
    for (int k = 0; k < 4; ++k) {
        gl_Position = target_position(corner[k]);
        EmitVertex();
    }
    EndPrimitive();
}
#elif defined FRAGMENT_SHADER
flat in vec2 g_c0;
flat in vec2 g_c1;
flat in vec2 g_c2;
flat in vec2 g_c3;
flat in vec2 g_lo;
flat in vec4 g_first;
flat in vec4 g_second;
out vec4 out_irradiance;
void main() {
    vec2 rel = floor(gl_FragCoord.xy) - g_lo;
    vec2 c0 = g_c0 - rel, c2 = g_c2 - rel;
    float first = g_first.a > 0.0 ? pixel_coverage(c0, g_c1 - rel, c2) : 0.0;
    float second = g_second.a > 0.0 ? pixel_coverage(c0, c2, g_c3 - rel) : 0.0;
    float covered = first + second;
    if (covered <= 0.0) discard;
    out_irradiance = vec4(g_first.rgb * first + g_second.rgb * second, covered);
}
#endif
