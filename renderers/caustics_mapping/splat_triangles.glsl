// The triangles program of a splat pass (splat_kernels.glsl, kernel `triangles`),
// included by caustic_splat.glsl and receiver_splat.glsl under TRIANGLES: one vertex
// per grid quad; the geometry shader turns a drawn quad into two triangles, each
// emitted as its bounding box of whole pixels with the triangle's corners (relative
// to the box) and the irradiance (W/m^2) at its corners; the fragment shader writes
// the integral of that linear irradiance over the part of its pixel the triangle
// covers (pixel_integrals), weighted as before by the covered area.
//
// Each triangle holds half the quad's flux, its grid-space share, so its mean
// irradiance is flux / area as with constant triangles; only the shape within it is
// linear. Constant triangles leave a sawtooth of one grid cell's period where the
// irradiance varies (their means step from triangle to triangle, and the two
// triangles of a curved quad differ), which the receiver's texels sample into moire
// fringes: on glass_sphere at grid 128 they were most of the caustic region's error
// (excess relMSE 4.1e-4 against 5e-5 with the linear shape; the exact paths of the
// decomposition study, triangles at 128^2: relMSE 4.6e-4 -> 1.1e-4, the 1024^2
// lattice 7.9e-5). The corners' irradiance is each vertex's flux over its share of
// the area of the triangles around it (a third of each), the piecewise-linear
// estimate of flux per unit area, limited so that no corner exceeds the range of its
// triangles' means (Barth and Jespersen's limiter: no new extremum at a fold, where
// the unlimited shape moved metal_ring's caustic error from 6.30e-3 to 6.51e-3).
//
// The including pass defines
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
flat out vec3 g_ea;
flat out vec3 g_eb;
flat out vec3 g_ec;

// A triangle whose longest side^2 exceeds SLIVER times its area (pixels) is drawn at
// constant irradiance: the float32 rounding of its barycentric integrals grows as
// the square of that ratio (about 1e-3 relative at 128). Slivers at a focus or a
// fold drawn linear without the limiter below changed glass_sphere's flux by 8e-5
// at grid 96; with the limiter the bundled scenes keep their flux to 5e-7 with or
// without this guard, and their errors do not move.
const float SLIVER = 128.0;

bool sliver(vec2 a, vec2 b, vec2 c) {
    vec2 u = b - a, w = c - a, v = c - b;
    float area = 0.5 * abs(u.x * w.y - u.y * w.x);
    return !(max(max(dot(u, u), dot(w, w)), dot(v, v)) < SLIVER * area);
}

// Draws triangle (a, b, c) of receiver area `area` holding `flux`: its irradiance is
// linear between the corners' estimates e scaled to keep the flux, with the linear
// part shrunk until no corner leaves [lo_e, hi_e], the range of the mean irradiance
// of the triangles around that corner (Barth and Jespersen's limiter; the mean, and
// so the flux, is kept). Slivers are drawn at their mean.
void emit_triangle(vec2 a, vec2 b, vec2 c, float area, vec3 flux, vec3 e[3], vec3 lo_e[3],
                   vec3 hi_e[3]) {
    if (!(area > 0.0)) return;
    vec3 mean = flux / area;                    // W/m^2
    vec3 sum = e[0] + e[1] + e[2];
    vec3 value[3];
    vec3 phi = vec3(sliver(a, b, c) ? 0.0 : 1.0);
    for (int k = 0; k < 3; ++k) {
        for (int i = 0; i < 3; ++i) {
            value[k][i] = sum[i] > 0.0 ? 3.0 * mean[i] * e[k][i] / sum[i] : mean[i];
            float delta = value[k][i] - mean[i];
            if (delta > 0.0) phi[i] = min(phi[i], max(hi_e[k][i] - mean[i], 0.0) / delta);
            else if (delta < 0.0) phi[i] = min(phi[i], min(lo_e[k][i] - mean[i], 0.0) / delta);
        }
    }
    vec2 lo = floor(min(min(a, b), c));
    vec2 hi = ceil(max(max(a, b), c));
    hi = max(hi, lo + 1.0);
    g_a = a - lo;
    g_b = b - lo;
    g_c = c - lo;
    g_lo = lo;
    g_ea = mean + phi * (value[0] - mean);
    g_eb = mean + phi * (value[1] - mean);
    g_ec = mean + phi * (value[2] - mean);
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
    // The 4 x 4 vertices around the quad (block (i, j) = vertex (qx - 1 + i,
    // qy - 1 + j)): their records, target pixels and whether they are splatted there.
    int record[16];
    vec2 pix[16];
    bool on[16];
    for (int b = 0; b < 16; ++b) {
        int x = qx - 1 + b % 4, y = qy - 1 + b / 4;
        record[b] = grid_record(view, clamp(x, 0, u_grid - 1), clamp(y, 0, u_grid - 1));
        on[b] = x >= 0 && y >= 0 && x < u_grid && y < u_grid && to_target(record[b], pix[b]);
        if (!on[b]) pix[b] = vec2(0.0);
    }
    // The 3 x 3 quads around it (this one at the centre, j = 4): drawn, and the
    // receiver areas (m^2) of their triangles (c0, c1, c2) and (c0, c2, c3).
    bool drawn[9];
    vec2 areas[9];
    ivec4 corners = ivec4(0, 1, 5, 4);       // block offsets of c0, c1, c2, c3
    for (int j = 0; j < 9; ++j) {
        int b0 = (j / 3) * 4 + j % 3;
        ivec4 k = b0 + corners;
        drawn[j] = false;
        areas[j] = vec2(0.0);
        if (!(on[k.x] && on[k.y] && on[k.z] && on[k.w])) continue;
        float receiver = splat_records[record[k.x] * 5 + 3].w;
        bool same = true;
        for (int m = 1; m < 4; ++m)
            same = same && abs(splat_records[record[k[m]] * 5 + 3].w - receiver) <= 0.5;
        vec2 c[4] = vec2[4](pix[k.x], pix[k.y], pix[k.z], pix[k.w]);
        if (!same || !quad_shape_drawn(view, qx - 1 + j % 3, qy - 1 + j / 3, c)) continue;
        drawn[j] = true;
        vec3 p0 = splat_records[record[k.x] * 5 + 2].xyz, p1 = splat_records[record[k.y] * 5 + 2].xyz;
        vec3 p2 = splat_records[record[k.z] * 5 + 2].xyz, p3 = splat_records[record[k.w] * 5 + 2].xyz;
        // The receiver's normal (mean of the corners'): a normal taken from the hits
        // themselves would tilt with their rounding on tiny triangles and, since only
        // |cos| <= 1 enters, always inflate the area (lost 4e-4 of the flux).
        vec3 n = splat_records[record[k.x] * 5 + 4].xyz + splat_records[record[k.y] * 5 + 4].xyz
            + splat_records[record[k.z] * 5 + 4].xyz + splat_records[record[k.w] * 5 + 4].xyz;
        n = dot(n, n) > 0.0 ? normalize(n) : vec3(0.0, 0.0, 1.0);
        areas[j] = max(vec2(triangle_area(c[0], c[1], c[2], p0, p1, p2, n),
                            triangle_area(c[0], c[2], c[3], p0, p2, p3, n)), vec2(0.0));
    }
    quad_flags[v_quad[0]] = drawn[4] ? 1 : 0;      // for the Gaussians drawn next
    if (!drawn[4]) return;
    // The mean irradiance of the drawn quads' triangles: half the quad's flux (an
    // eighth of each corner's) over each triangle's area.
    vec3 means[18];
    for (int j = 0; j < 9; ++j) {
        int b0 = (j / 3) * 4 + j % 3;
        vec3 half_flux = vec3(0.0);
        for (int m = 0; m < 4; ++m)
            half_flux += 0.125 * splat_records[record[b0 + corners[m]] * 5 + 3].rgb;
        means[2 * j] = areas[j].x > 0.0 ? half_flux / areas[j].x : vec3(0.0);
        means[2 * j + 1] = areas[j].y > 0.0 ? half_flux / areas[j].y : vec3(0.0);
    }
    // Each corner's irradiance: the flux it gives its drawn quads (a quarter per
    // quad) over a third of the area of the triangles around it that have it as a
    // corner (its share of their area under linear interpolation); and the range of
    // those triangles' means.
    ivec2 offset[4] = ivec2[4](ivec2(0, 0), ivec2(1, 0), ivec2(1, 1), ivec2(0, 1));
    vec3 e[4], lo_e[4], hi_e[4];
    for (int k = 0; k < 4; ++k) {
        float quads = 0.0, around = 0.0;
        lo_e[k] = vec3(3.0e38);
        hi_e[k] = vec3(0.0);
        for (int m = 0; m < 4; ++m) {            // the quad of which it is corner m
            ivec2 q = offset[k] - offset[m] + 1;
            int j = q.y * 3 + q.x;
            if (!drawn[j]) continue;
            quads += 1.0;
            if (m != 3 && areas[j].x > 0.0) {    // in triangle (c0, c1, c2)
                around += areas[j].x;
                lo_e[k] = min(lo_e[k], means[2 * j]);
                hi_e[k] = max(hi_e[k], means[2 * j]);
            }
            if (m != 1 && areas[j].y > 0.0) {    // in triangle (c0, c2, c3)
                around += areas[j].y;
                lo_e[k] = min(lo_e[k], means[2 * j + 1]);
                hi_e[k] = max(hi_e[k], means[2 * j + 1]);
            }
        }
        int b = (offset[k].y + 1) * 4 + offset[k].x + 1;
        vec3 flux = splat_records[record[b] * 5 + 3].rgb;
        e[k] = around > 0.0 ? 0.25 * quads * flux / (around / 3.0) : vec3(0.0);
    }
    vec2 c0 = pix[5], c1 = pix[6], c2 = pix[10], c3 = pix[9];
    emit_triangle(c0, c1, c2, areas[4].x, means[8] * areas[4].x,
                  vec3[3](e[0], e[1], e[2]), vec3[3](lo_e[0], lo_e[1], lo_e[2]),
                  vec3[3](hi_e[0], hi_e[1], hi_e[2]));
    emit_triangle(c0, c2, c3, areas[4].y, means[9] * areas[4].y,
                  vec3[3](e[0], e[2], e[3]), vec3[3](lo_e[0], lo_e[2], lo_e[3]),
                  vec3[3](hi_e[0], hi_e[2], hi_e[3]));
}
#elif defined FRAGMENT_SHADER
flat in vec2 g_a;
flat in vec2 g_b;
flat in vec2 g_c;
flat in vec2 g_lo;
flat in vec3 g_ea;
flat in vec3 g_eb;
flat in vec3 g_ec;
out vec4 out_irradiance;
void main() {
    vec2 rel = floor(gl_FragCoord.xy) - g_lo;
    vec2 lambda;
    float covered = pixel_integrals(g_a - rel, g_b - rel, g_c - rel, lambda);
    if (covered <= 0.0) discard;
    vec3 value = g_ea * (covered - lambda.x - lambda.y) + g_eb * lambda.x + g_ec * lambda.y;
    out_irradiance = vec4(value, covered);
}
#endif

