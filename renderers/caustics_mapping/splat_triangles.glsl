// The triangles program of a splat pass (splat_kernels.glsl, kernel `triangles`),
// included by caustic_splat.glsl and receiver_splat.glsl under TRIANGLES: one vertex
// per grid quad; the geometry shader turns a drawn quad into two triangles, emitted
// together as the quad's bounding box of whole pixels with the corners (relative to
// the box) and the irradiance (W/m^2) at each triangle's corners; the fragment
// shader writes, per triangle, the integral of that linear irradiance over the part
// of its pixel the triangle covers (pixel_integrals).
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
//
// Three stages, each over the whole grid, share the neighbours' work:
//   QUAD_PASS (compute, one invocation per quad): whether the quad is drawn
//     (quad_flags, which the Gaussians read too), the receiver areas of its two
//     triangles and their mean irradiance (quad_data, quad_means);
//   CORNER_PASS (compute, one per vertex): the vertex's irradiance estimate e, the
//     range [lo_e, hi_e] of the means of the drawn triangles around it, and its hit
//     in target pixels (corner_data), which the draw reads instead of projecting
//     every corner of every quad again (llvmpipe runs a geometry shader on one
//     thread: glass_sphere's triangle draws 40.8 -> 36.7 ms a frame, the same maps
//     bit for bit);
//   the draw (geometry shader, one per quad): reads them and emits its triangles.
//   Both triangles of a quad are drawn in one box of whole pixels, the quad's.
// A geometry shader that gathered the 3 x 3 quads around its own took 2.5x as long.
// The draw's work in a third compute pass, with a vertex shader drawing six vertices
// per quad from its results, made the same maps bit for bit but took longer
// (glass_sphere, strong, both maps: 63-65 -> 70-73 ms a frame on llvmpipe).

#if defined GEOMETRY_SHADER || defined COMPUTE_SHADER
// quad q: x 1 if drawn (0 not), y and z the receiver areas (m^2) of its triangles
// (c0, c1, c2) and (c0, c2, c3), w 1 where routed to the coarser target (u_route_px);
// quad_means[2q], [2q + 1]: their mean irradiance
// (rgb, W/m^2): half the quad's flux over each area.
layout(std430, binding = 2) buffer QuadData { vec4 quad_data[]; };
layout(std430, binding = 3) buffer QuadMeans { vec4 quad_means[]; };
// record i: corner_data[3i] rgb e, [3i + 1] rgb lo_e, [3i + 2] rgb hi_e (W/m^2);
// the w of the first two: the hit in target pixels (x, y; where it lands there).
layout(std430, binding = 4) buffer CornerData { vec4 corner_data[]; };
// Per grid quad, 1 where its rim patch is drawn instead (rim_patches.glsl), read
// with u_handoff = 1.
layout(std430, binding = 8) readonly buffer Handoff { int handoff[]; };
uniform int u_handoff;
// With a finer target for the triangles than the Gaussians' (TrianglesApart): a quad
// wider than u_route_px pixels of the Gaussians' target is routed there (0: none;
// quad_data's w). u_route: 0 the draw takes every drawn quad; 1 those routed finer;
// 2 those routed coarser, their corners (finer target pixels) times 1 / u_px_scale,
// exact (a power of two; to_target is linear in the map's size and origin).
uniform float u_route_px;
uniform int u_route;

int quad_index(int view, int qx, int qy) {
    return (view * (u_grid - 1) + qy) * (u_grid - 1) + qx;
}

// Quad q's view, its grid position (qx, qy) and its corners' records c0 .. c3:
// (qx, qy), (qx + 1, qy), (qx + 1, qy + 1), (qx, qy + 1).
void quad_corners(int q, out int view, out int qx, out int qy, out int record[4]) {
    int per_view = (u_grid - 1) * (u_grid - 1);
    view = q / per_view;
    int local = q - view * per_view;
    qx = local % (u_grid - 1);
    qy = local / (u_grid - 1);
    record = int[4](grid_record(view, qx, qy), grid_record(view, qx + 1, qy),
                    grid_record(view, qx + 1, qy + 1), grid_record(view, qx, qy + 1));
}
#endif

#if defined COMPUTE_SHADER
layout(local_size_x = 64) in;
uniform int u_count;                // quads (QUAD_PASS) or records (CORNER_PASS)

#if defined QUAD_PASS
void main() {
    int q = int(gl_GlobalInvocationID.x);
    if (q >= u_count) return;
    int view, qx, qy, record[4];
    quad_corners(q, view, qx, qy, record);
    vec2 c[4];
    bool drawn = true;
    for (int k = 0; k < 4; ++k) drawn = to_target(record[k], c[k]) && drawn;
    float receiver = splat_records[record[0] * 5 + 3].w;
    for (int m = 1; m < 4; ++m)
        drawn = drawn && abs(splat_records[record[m] * 5 + 3].w - receiver) <= 0.5;
    drawn = drawn && quad_shape_drawn(view, qx, qy, c);
    // A quad left to its rim patch is not drawn here, and counts as drawn for its
    // corners' Gaussians (quad_flags 2): the patch carries its flux.
    bool patched = u_handoff == 1 && handoff[q] != 0;
    drawn = drawn && !patched;
    vec2 areas = vec2(0.0);
    if (drawn) {
        vec3 p0 = splat_records[record[0] * 5 + 2].xyz, p1 = splat_records[record[1] * 5 + 2].xyz;
        vec3 p2 = splat_records[record[2] * 5 + 2].xyz, p3 = splat_records[record[3] * 5 + 2].xyz;
        // The receiver's normal (mean of the corners'): a normal taken from the hits
        // themselves would tilt with their rounding on tiny triangles and, since only
        // |cos| <= 1 enters, always inflate the area (lost 4e-4 of the flux).
        vec3 n = splat_records[record[0] * 5 + 4].xyz + splat_records[record[1] * 5 + 4].xyz
            + splat_records[record[2] * 5 + 4].xyz + splat_records[record[3] * 5 + 4].xyz;
        n = dot(n, n) > 0.0 ? normalize(n) : vec3(0.0, 0.0, 1.0);
        areas = max(vec2(triangle_area(c[0], c[1], c[2], p0, p1, p2, n),
                         triangle_area(c[0], c[2], c[3], p0, p2, p3, n)), vec2(0.0));
    }
    // Half the quad's flux (an eighth of each corner's) over each triangle's area.
    vec3 half_flux = vec3(0.0);
    for (int m = 0; m < 4; ++m) half_flux += 0.125 * splat_records[record[m] * 5 + 3].rgb;
    quad_flags[q] = patched ? 2 : drawn ? 1 : 0;
    vec2 extent = max(max(c[0], c[1]), max(c[2], c[3]))
        - min(min(c[0], c[1]), min(c[2], c[3]));
    bool coarse = u_route_px > 0.0 && max(extent.x, extent.y) > u_route_px * u_px_scale;
    quad_data[q] = vec4(drawn ? 1.0 : 0.0, areas, coarse ? 1.0 : 0.0);
    quad_means[2 * q] = vec4(areas.x > 0.0 ? half_flux / areas.x : vec3(0.0), 0.0);
    quad_means[2 * q + 1] = vec4(areas.y > 0.0 ? half_flux / areas.y : vec3(0.0), 0.0);
}
#elif defined CORNER_PASS
// Each vertex's irradiance: the flux it gives its drawn quads (a quarter per quad)
// over a third of the area of the triangles around it that have it as a corner (its
// share of their area under linear interpolation); and the range of those
// triangles' means.
void main() {
    int i = int(gl_GlobalInvocationID.x);
    if (i >= u_count) return;
    int view, tx, ty;
    record_vertex(i, view, tx, ty);
    ivec2 offset[4] = ivec2[4](ivec2(0, 0), ivec2(1, 0), ivec2(1, 1), ivec2(0, 1));
    float quads = 0.0, around = 0.0;
    vec3 lo_e = vec3(3.0e38), hi_e = vec3(0.0);
    for (int m = 0; m < 4; ++m) {                // the quad of which it is corner m
        ivec2 o = ivec2(tx, ty) - offset[m];
        if (o.x < 0 || o.y < 0 || o.x >= u_grid - 1 || o.y >= u_grid - 1) continue;
        int q = quad_index(view, o.x, o.y);
        vec4 data = quad_data[q];
        if (data.x < 0.5) continue;
        quads += 1.0;
        if (m != 3 && data.y > 0.0) {           // in triangle (c0, c1, c2)
            around += data.y;
            lo_e = min(lo_e, quad_means[2 * q].rgb);
            hi_e = max(hi_e, quad_means[2 * q].rgb);
        }
        if (m != 1 && data.z > 0.0) {           // in triangle (c0, c2, c3)
            around += data.z;
            lo_e = min(lo_e, quad_means[2 * q + 1].rgb);
            hi_e = max(hi_e, quad_means[2 * q + 1].rgb);
        }
    }
    vec3 flux = splat_records[i * 5 + 3].rgb;
    vec3 e = around > 0.0 ? 0.25 * quads * flux / (around / 3.0) : vec3(0.0);
    vec2 pix;
    to_target(i, pix);
    corner_data[3 * i] = vec4(e, pix.x);
    corner_data[3 * i + 1] = vec4(lo_e, pix.y);
    corner_data[3 * i + 2] = vec4(hi_e, 0.0);
}
#endif

#elif defined VERTEX_SHADER
flat out int v_quad;
void main() {
    v_quad = gl_VertexID;
    gl_Position = vec4(0.0);
}
#elif defined GEOMETRY_SHADER
layout(points) in;
layout(triangle_strip, max_vertices = 4) out;
flat in int v_quad[];
// The quad's corners relative to g_lo (pixels), and the irradiance (W/m^2) at the
// corners of its triangles (c0, c1, c2) and (c0, c2, c3); a triangle not drawn has
// zeros and g_drawn's component 0. Both are drawn in one box, the quad's: a
// triangle's own box is nearly its quad's, so a box per triangle rasterised most
// pixels twice.
flat out vec2 g_c0;
flat out vec2 g_c1;
flat out vec2 g_c2;
flat out vec2 g_c3;
flat out vec2 g_lo;
flat out vec3 g_first[3];
flat out vec3 g_second[3];
flat out vec2 g_drawn;

const float SLIVER = 128.0;

bool sliver(vec2 a, vec2 b, vec2 c) {
    vec2 u = b - a, w = c - a, v = c - b;
    float area = 0.5 * abs(u.x * w.y - u.y * w.x);
    return !(max(max(dot(u, u), dot(w, w)), dot(v, v)) < SLIVER * area);
}

// The corner values of triangle (a, b, c) of receiver area `area` holding `flux`:
// its irradiance is linear between the corners' estimates e scaled to keep the flux,
// with the linear part shrunk until no corner leaves [lo_e, hi_e], the range of the
// mean irradiance of the triangles around that corner (Barth and Jespersen's
// limiter; the mean, and so the flux, is kept). Slivers are drawn at their mean.
// False (values zero) for a triangle of no area, which is not drawn.
bool triangle_values(vec2 a, vec2 b, vec2 c, float area, vec3 flux, vec3 e[3],
                     vec3 lo_e[3], vec3 hi_e[3], out vec3 corner[3]) {
    for (int k = 0; k < 3; ++k) corner[k] = vec3(0.0);
    if (!(area > 0.0)) return false;
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
    for (int k = 0; k < 3; ++k) corner[k] = mean + phi * (value[k] - mean);
    return true;
}

// A long quad lying across the pixel grid (the halo's radial slivers, the bunny's
// stretched sheets) fills a small part of its axis-aligned box. Where the box along
// the quad's longer diagonal has at most 0.8 of its pixels, `corner` (a strip:
// lo-lo, hi-lo, lo-hi, hi-hi) becomes that box grown by REACH: every pixel the quad
// touches has its centre within half a pixel diagonal (0.707) of it, and the margin
// covers the rasteriser's snapping of the corners (1/256 px on llvmpipe), so the
// same pixels get a nonzero part (glass_sphere strong: caustic-map triangles 18.8 ->
// 15.9 ms; at 0.5 of the box, 16.2 ms).
const float REACH = 0.75;
void oriented_box(vec2 c[4], float box_area, inout vec2 corner[4]) {
    if (u_tight_boxes == 0) return;
    vec2 d1 = c[2] - c[0], d2 = c[3] - c[1];
    vec2 a = dot(d1, d1) >= dot(d2, d2) ? d1 : d2;
    if (!(dot(a, a) > 0.0)) return;
    a = normalize(a);
    vec2 b = vec2(-a.y, a.x);
    vec2 s = vec2(3.0e38, -3.0e38), t = vec2(3.0e38, -3.0e38);
    for (int k = 0; k < 4; ++k) {
        float x = dot(c[k] - c[0], a), y = dot(c[k] - c[0], b);
        s = vec2(min(s.x, x), max(s.y, x));
        t = vec2(min(t.x, y), max(t.y, y));
    }
    s += vec2(-REACH, REACH);
    t += vec2(-REACH, REACH);
    if ((s.y - s.x) * (t.y - t.x) > 0.8 * box_area) return;
    corner[0] = c[0] + s.x * a + t.x * b;
    corner[1] = c[0] + s.y * a + t.x * b;
    corner[2] = c[0] + s.x * a + t.y * b;
    corner[3] = c[0] + s.y * a + t.y * b;
}

void main() {
    int q = v_quad[0];
    vec4 data = quad_data[q];
    if (data.x < 0.5) return;
    bool coarse = data.w > 0.5;
    if ((u_route == 1 && coarse) || (u_route == 2 && !coarse)) return;
    float to_pixels = u_route == 2 ? 1.0 / u_px_scale : 1.0;
    int view, qx, qy, record[4];
    quad_corners(q, view, qx, qy, record);
    vec2 c[4];
    vec3 e[4], lo_e[4], hi_e[4];
    for (int k = 0; k < 4; ++k) {
        c[k] = to_pixels * vec2(corner_data[3 * record[k]].w, corner_data[3 * record[k] + 1].w);
        e[k] = corner_data[3 * record[k]].rgb;
        lo_e[k] = corner_data[3 * record[k] + 1].rgb;
        hi_e[k] = corner_data[3 * record[k] + 2].rgb;
    }
    vec3 first[3], second[3];
    bool one = triangle_values(c[0], c[1], c[2], data.y, quad_means[2 * q].rgb * data.y,
                               vec3[3](e[0], e[1], e[2]), vec3[3](lo_e[0], lo_e[1], lo_e[2]),
                               vec3[3](hi_e[0], hi_e[1], hi_e[2]), first);
    bool two = triangle_values(c[0], c[2], c[3], data.z, quad_means[2 * q + 1].rgb * data.z,
                               vec3[3](e[0], e[2], e[3]), vec3[3](lo_e[0], lo_e[2], lo_e[3]),
                               vec3[3](hi_e[0], hi_e[2], hi_e[3]), second);
    if (!one && !two) return;
    vec2 lo = floor(min(min(c[0], c[1]), min(c[2], c[3])));
    vec2 hi = ceil(max(max(c[0], c[1]), max(c[2], c[3])));
    hi = max(hi, lo + 1.0);
    vec2 corner[4] = vec2[4](lo, vec2(hi.x, lo.y), vec2(lo.x, hi.y), hi);
    oriented_box(c, (hi.x - lo.x) * (hi.y - lo.y), corner);
    for (int k = 0; k < 4; ++k) {
        g_c0 = c[0] - lo;
        g_c1 = c[1] - lo;
        g_c2 = c[2] - lo;
        g_c3 = c[3] - lo;
        g_lo = lo;
        g_first = first;
        g_second = second;
        g_drawn = vec2(one ? 1.0 : 0.0, two ? 1.0 : 0.0);
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
flat in vec3 g_first[3];
flat in vec3 g_second[3];
flat in vec2 g_drawn;
out vec4 out_irradiance;
void main() {
    vec2 rel = floor(gl_FragCoord.xy) - g_lo;
    vec2 c0 = g_c0 - rel, c2 = g_c2 - rel;
    vec3 value = vec3(0.0);
    float covered = 0.0;
    vec2 lambda;
    // The diagonal (c0, c2) is an edge of both triangles: its integrals are found
    // once; the second triangle is read as (c0, c3, c2), so
    // lambda holds c3's integral first.
    vec3 diagonal = vec3(0.0);
    bool known = false;
    if (g_drawn.x > 0.5) {
        float part = pixel_integrals(c0, g_c1 - rel, c2, diagonal, known, lambda);
        if (part > 0.0) {
            value += g_first[0] * (part - lambda.x - lambda.y) + g_first[1] * lambda.x
                + g_first[2] * lambda.y;
            covered += part;
        }
    }
    if (g_drawn.y > 0.5) {
        float part = pixel_integrals(c0, g_c3 - rel, c2, diagonal, known, lambda);
        if (part > 0.0) {
            value += g_second[0] * (part - lambda.x - lambda.y) + g_second[1] * lambda.y
                + g_second[2] * lambda.x;
            covered += part;
        }
    }
    if (covered <= 0.0) discard;
    out_irradiance = vec4(value, covered);
}
#endif
