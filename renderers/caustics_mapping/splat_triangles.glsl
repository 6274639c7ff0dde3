// The triangles program of a splat pass (splat_kernels.glsl, kernel `triangles`),
// included by caustic_splat.glsl and receiver_splat.glsl under TRIANGLES: one vertex
// per grid quad; the geometry shader turns a drawn quad into two triangles, each
// emitted as its bounding box of whole pixels with the triangle's corners (relative
// to the box) and its irradiance (W/m^2: half the quad's flux over the triangle's
// area on the receiver); the fragment shader weights the irradiance by the area of
// its pixel the triangle covers. The including pass defines
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
layout(triangle_strip, max_vertices = 8) out;
flat in int v_quad[];
flat out vec2 g_a;
flat out vec2 g_b;
flat out vec2 g_c;
flat out vec2 g_lo;
flat out vec3 g_value;

void emit_triangle(vec2 a, vec2 b, vec2 c, vec3 pa, vec3 pb, vec3 pc, vec3 n, vec3 flux) {
    float area = triangle_area(a, b, c, pa, pb, pc, n);        // m^2 on the receiver
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

