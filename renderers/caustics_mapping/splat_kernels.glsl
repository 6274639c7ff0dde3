// Splat kernels shared by the caustic-map and receiver-map passes (included after
// common.glsl). Every kernel conserves each grid vertex's flux exactly in the
// target it is drawn into:
//   points     one Gaussian of a fixed width per vertex (the paper's splat);
//   footprint  one Gaussian per vertex whose covariance is footprint_scale^2 times
//              the outer products of the grid's hit differences along x and y
//              (ray differentials of the grid; Wyman & Dachsbacher 2006, Frisvad et
//              al. 2014), plus (0.5 px)^2 so no splat falls between pixel centres;
//   triangles  each grid quad whose four corners all land on the target becomes two
//              triangles between the hits, each holding its share of the quad's flux
//              (webgl-water; Ernst et al. 2005) at an irradiance linear over it
//              (splat_triangles.glsl). A vertex gives a quarter of its flux
//              to each of its four quads; the quarters of quads that cannot be drawn
//              (a corner missing, on another receiver or face, a fold where the
//              quad's two triangles have opposite orientation, or a triangle wider
//              than u_max_triangle pixels, or a rim sliver) go to a footprint
//              Gaussian of the vertex. Rim slivers: where the light grazes a
//              refracting object's silhouette its mapping to the receiver diverges
//              (a glass sphere's outer three grid rings spread from 1 m to 4 m on
//              glass_sphere's floor), and the grid's staircase silhouette makes
//              neighbouring quads there reach very different distances: drawn as
//              triangles they are long radial slivers that leave the halo in radial
//              streaks. Such quads (RIM_STEPS, STRETCH_PX, STRETCH_RATIO) go to round
//              Gaussians instead.
// Triangles are drawn exactly: each pixel of a triangle's bounding box gets the
// integral of the triangle's irradiance over the part of the pixel it covers
// (pixel_integrals), so the pixels' values sum to the triangle's flux.
//
// The record buffer (caustic_trace.glsl's layout) is read as an SSBO: record i is
// grid vertex (view, tx, ty) with i = (view * u_grid + ty) * u_grid + tx. Rim patches
// (u_patches = 1, caustic_trace.glsl) are drawn as views of their own (u_grid = the
// patch's vertices per side): their borders lie inside the object, so they are not
// a silhouette, and a border vertex's Gaussian carries only the quarters of its own
// patch's quads (the neighbouring quad or patch holds its own copy of the vertex).
// The grid's quads that have a patch are left to it (u_handoff, handoff[]): not
// drawn, and no vertex's Gaussian carries their quarters.
//
// Each pass defines, before including this file:
//   bool to_target(int record, out vec2 pix)  // the record's hit in target pixels,
//                                            // false if it is not splatted there

layout(std430, binding = 0) readonly buffer SplatRecords { vec4 splat_records[]; };
#if defined VERTEX_SHADER || defined GEOMETRY_SHADER || defined COMPUTE_SHADER
// Triangles: whether each grid quad q = (view * (u_grid - 1) + qy) * (u_grid - 1) + qx
// is drawn (quad_shape_drawn), written by the triangles' quad pass
// (splat_triangles.glsl), which runs first, and read by the Gaussians' vertex shader
// (gaussian_share): one evaluation per quad instead of four per vertex, which took a
// third of the splat passes.
layout(std430, binding = 1) buffer QuadFlags { int quad_flags[]; };
#endif

uniform int u_grid;               // vertex grid per object view
uniform int u_splat_mode;         // 0 points, 1 footprint, 2 triangles
uniform float u_footprint_scale;  // footprint covariance scale
uniform float u_max_triangle;     // pixels: wider triangles fall back to Gaussians
uniform float u_px_scale;         // target pixels per pixel of the map whose thresholds
                                  // (u_max_triangle, STRETCH_PX) decide the kernels
uniform float u_sigma;            // points: Gaussian standard deviation (caustic-map texels)
uniform float u_cut;              // Gaussian cut-off radius (sigmas)
uniform float u_max_radius;       // Gaussian sprite radius cap (target pixels)
uniform int u_tight_boxes;        // 1: long kernels drawn in boxes along their axes
uniform int u_patches;            // 1: the records are rim patches

const int SPLAT_POINTS = 0;
const int SPLAT_FOOTPRINT = 1;
const int SPLAT_TRIANGLES = 2;
// Triangles near the silhouette (see the header): a quad with a corner within
// RIM_STEPS grid steps of the silhouette whose longest side exceeds STRETCH_PX target
// pixels and whose side^2 / area exceeds STRETCH_RATIO (a sliver) is not drawn, and
// the Gaussians of vertices there are round (glass_sphere at 128^2 against its
// golden reference: full-map excess relMSE 5.1e-4 -> 3.8e-4; values between 4 and
// 24 px and 16 and 96 measured 3.8e-4 to 1.0e-3, these the best).
const int RIM_STEPS = 3;
const float STRETCH_PX = 12.0;
const float STRETCH_RATIO = 96.0;

#if defined VERTEX_SHADER || defined GEOMETRY_SHADER || defined COMPUTE_SHADER
bool to_target(int record, out vec2 pix);

int grid_record(int view, int tx, int ty) {
    return (view * u_grid + ty) * u_grid + tx;
}

// The grid vertex (view, tx, ty) of record i: grid_record's inverse.
void record_vertex(int i, out int view, out int tx, out int ty) {
    view = i / (u_grid * u_grid);
    int local = i - view * u_grid * u_grid;
    tx = local % u_grid;
    ty = local / u_grid;
}

// The hit of neighbour (tx + dx, ty + dy) in target pixels, if it is splatted there
// and on the same receiver as `receiver`.
bool neighbour(int view, int tx, int ty, int dx, int dy, float receiver, out vec2 pix) {
    pix = vec2(0.0);
    int x = tx + dx, y = ty + dy;
    if (x < 0 || y < 0 || x >= u_grid || y >= u_grid) return false;
    int i = grid_record(view, x, y);
    if (abs(splat_records[i * 5 + 3].w - receiver) > 0.5) return false;
    return to_target(i, pix);
}

// Derivative of the hit along one grid axis (target pixels per grid step): central
// difference, or one-sided where a neighbour is missing; false when both are.
bool grid_derivative(int view, int tx, int ty, ivec2 axis, float receiver, vec2 centre,
                     out vec2 derivative) {
    vec2 a, b;
    bool has_a = neighbour(view, tx, ty, axis.x, axis.y, receiver, a);
    bool has_b = neighbour(view, tx, ty, -axis.x, -axis.y, receiver, b);
    derivative = has_a && has_b ? 0.5 * (a - b) : has_a ? a - centre : has_b ? centre - b
        : vec2(0.0);
    return has_a || has_b;
}

// Whether grid vertex (view, tx, ty) lies within RIM_STEPS grid steps (along the
// grid's axes) of a vertex that shows no object (status empty; the grid's border
// counts as empty): near the object's silhouette seen from the light.
bool near_silhouette(int view, int tx, int ty) {
    for (int step = 1; step <= RIM_STEPS; ++step) {
        for (int k = 0; k < 4; ++k) {
            ivec2 o = step * ivec2(k == 0 ? 1 : k == 1 ? -1 : 0, k == 2 ? 1 : k == 3 ? -1 : 0);
            int x = tx + o.x, y = ty + o.y;
            if (x < 0 || y < 0 || x >= u_grid || y >= u_grid) {
                if (u_patches == 1) continue;
                return true;
            }
            if (splat_records[grid_record(view, x, y) * 5 + 2].w < 0.5) return true;
        }
    }
    return false;
}

// Covariance (target pixels^2) of a footprint splat of record (view, tx, ty) hit at
// `centre`; `fallback_sigma` (pixels) where no neighbour is known.
mat2 footprint_covariance(int view, int tx, int ty, vec2 centre, float fallback_sigma) {
    float receiver = splat_records[grid_record(view, tx, ty) * 5 + 3].w;
    vec2 ex, ey;
    bool has_x = grid_derivative(view, tx, ty, ivec2(1, 0), receiver, centre, ex);
    bool has_y = grid_derivative(view, tx, ty, ivec2(0, 1), receiver, centre, ey);
    if (!has_x && !has_y) return mat2(fallback_sigma * fallback_sigma);
    if (!has_x) ex = vec2(-ey.y, ey.x);      // square cell: the missing axis turned 90°
    if (!has_y) ey = vec2(-ex.y, ex.x);
    float k = u_footprint_scale * u_footprint_scale;
    if (u_splat_mode == SPLAT_TRIANGLES && u_patches == 0 && near_silhouette(view, tx, ty)) {
        // Round, of the larger axis: the flux of rim slivers is spread across the
        // streaks their neighbours' slivers would leave, not along them.
        float r2 = max(dot(ex, ex), dot(ey, ey));
        return k * mat2(r2) + mat2(0.25);
    }
    return k * (outerProduct(ex, ex) + outerProduct(ey, ey)) + mat2(0.25);
}

// Whether quad (qx, qy) (corners (qx, qy), (qx+1, qy), (qx+1, qy+1), (qx, qy+1)),
// whose corners all land on one receiver and on the target at pixels c, is drawn as
// two triangles: not too wide, not a rim sliver, not folded.
bool quad_shape_drawn(int view, int qx, int qy, vec2 c[4]) {
    vec2 lo = min(min(c[0], c[1]), min(c[2], c[3]));
    vec2 hi = max(max(c[0], c[1]), max(c[2], c[3]));
    if (any(greaterThan(hi - lo, vec2(u_max_triangle)))) return false;
    vec2 e1 = c[1] - c[0], e2 = c[2] - c[0], e3 = c[3] - c[0];
    float a1 = e1.x * e2.y - e1.y * e2.x;     // twice the signed areas
    float a2 = e2.x * e3.y - e2.y * e3.x;
    float longest = max(max(length(e1), length(e3)),
                        max(length(c[2] - c[1]), length(c[2] - c[3])));
    float area = 0.5 * abs(a1 + a2);          // the quad's area (pixels^2)
    if (u_patches == 0 && longest > STRETCH_PX * u_px_scale
        && longest * longest > STRETCH_RATIO * area
        && (near_silhouette(view, qx, qy) || near_silhouette(view, qx + 1, qy + 1)))
        return false;                         // a rim sliver (see RIM_STEPS)
    return a1 * a2 > 0.0;                     // same orientation, neither degenerate
}

// Share of a vertex's flux that its Gaussian carries with triangle splats: the
// quarters of its four quads that are not drawn (1 with the other kernels), as the
// triangles' pass recorded them in quad_flags.
float gaussian_share(int view, int tx, int ty) {
    if (u_splat_mode != SPLAT_TRIANGLES) return 1.0;
    float drawn = 0.0;
    int side = u_grid - 1;
    for (int qy = ty - 1; qy <= ty; ++qy)
        for (int qx = tx - 1; qx <= tx; ++qx)
            if (qx >= 0 && qy >= 0 && qx < side && qy < side
                ? quad_flags[(view * side + qy) * side + qx] != 0 : u_patches == 1)
                drawn += 1.0;
    return 1.0 - 0.25 * drawn;
}

// Sum over the pixels of [lo, hi) within `cut` Mahalanobis radii of c of
// exp(-q^T S^-1 q / 2), q = pixel centre - c: each fragment's weight divided by it
// makes the splat's weights sum to one whatever its sub-pixel position.
// Along a row (qy fixed) e(qx) = q^T S^-1 q = A qx^2 + 2 B qx qy + C qy^2 is a
// quadratic, so from the row's first pixel inside the cut-off ellipse on, both e and
// the weight follow by recurrence: e += de, de += 2A, and w *= exp(-de / 2) with
// exp(-de / 2) *= exp(-A); two exp() per row instead of one per pixel (the weights
// agree with the fragments' own exp() to a few float32 roundings). Inside the
// ellipse w >= exp(-cut^2 / 2) and |de| <= 2 cut sqrt(A) + A, so nothing under- or
// overflows however thin the ellipse.
float gaussian_norm(vec2 c, mat2 inv, float radius, float cut, vec2 lo, vec2 hi) {
    float a = inv[0][0], b = 0.5 * (inv[0][1] + inv[1][0]), d = inv[1][1];
    float cut2 = cut * cut;
    float total = 0.0;
    for (float y = floor(c.y - radius) + 0.5; y <= c.y + radius; y += 1.0) {
        if (y < lo.y || y >= hi.y) continue;
        float qy = y - c.y;
        // The row's span of the ellipse: A qx^2 + 2 B qy qx + C qy^2 <= cut^2.
        float disc = b * b * qy * qy - a * (d * qy * qy - cut2);
        if (!(disc >= 0.0)) continue;
        float half_width = sqrt(disc) / a, mid = -b * qy / a;
        float x = max(floor(c.x + mid - half_width) + 0.5, floor(c.x - radius) + 0.5);
        float x_end = min(c.x + mid + half_width + 1.0, c.x + radius);
        float qx = x - c.x;
        float e = (a * qx + 2.0 * b * qy) * qx + d * qy * qy;
        float de = a * (2.0 * qx + 1.0) + 2.0 * b * qy;    // e(qx + 1) - e(qx)
        float w = exp(-0.5 * e), step = exp(-0.5 * de);
        float turn = exp(-a);                               // step's own ratio
        for (; x <= x_end; x += 1.0) {
            if (e <= cut2 && x >= lo.x && x < hi.x) total += w;
            e += de;
            de += 2.0 * a;
            w *= step;
            step *= turn;
        }
    }
    return total;
}

// The Gaussian's covariance shrunk so its cut-off radius fits `max_radius` pixels;
// returns the radius (pixels) its sprite must reach. Only the part above
// (0.5 px)^2 I is shrunk, so no axis falls below half a pixel (a thinner ellipse
// could miss every pixel centre and drop the vertex's flux).
float fit_radius(inout mat2 cov, float cut, float max_radius) {
    float tr = cov[0][0] + cov[1][1];
    float det = determinant(cov);
    float largest = 0.5 * tr + sqrt(max(0.25 * tr * tr - det, 0.0));
    float radius = cut * sqrt(largest);
    float limit = (max_radius / cut) * (max_radius / cut);
    if (radius > max_radius && largest > 0.25 && limit > 0.25) {
        float s = (limit - 0.25) / (largest - 0.25);
        cov = s * (cov - mat2(0.25)) + mat2(0.25);
        radius = max_radius;
    }
    return radius;
}
#endif

// Integrals along segment p -> q, clipped to the strip lo.y <= y <= hi.y, of
// clamp(x, lo.x, hi.x) dy, clamp(x, lo.x, hi.x)^2 / 2 dy and y clamp(x, lo.x, hi.x) dy:
// by Green's theorem their sums over a triangle's edges (anticlockwise) are the area
// and the first moments (x, y) of its part inside the box [lo, hi] (d/dx of
// clamp(x, lo.x, hi.x) is 1 within the box's x-range and 0 outside it, and the
// strip's borders have dy = 0). Exact: the segment's parameters where x crosses
// lo.x and hi.x cut it into at most three pieces on each of which X = clamp(x) and y
// are linear in the parameter, so with the values X0, X1 and Y0, Y1 at a piece's
// ends (length h) the integrals are h (X0 + X1) / 2, h (X0^2 + X0 X1 + X1^2) / 6
// and h (2 X0 Y0 + X0 Y1 + X1 Y0 + 2 X1 Y1) / 6, times dy.
vec3 edge_moments(vec2 p, vec2 q, vec2 lo, vec2 hi) {
    float dy = q.y - p.y;
    if (dy == 0.0) return vec3(0.0);
    float t0 = clamp((lo.y - p.y) / dy, 0.0, 1.0), t1 = clamp((hi.y - p.y) / dy, 0.0, 1.0);
    float ta = min(t0, t1), tb = max(t0, t1);
    if (tb <= ta) return vec3(0.0);
    float dx = q.x - p.x;
    float s0 = dx != 0.0 ? (lo.x - p.x) / dx : ta, s1 = dx != 0.0 ? (hi.x - p.x) / dx : ta;
    vec4 t = vec4(ta, clamp(min(s0, s1), ta, tb), clamp(max(s0, s1), ta, tb), tb);
    vec4 x = clamp(p.x + t * dx, lo.x, hi.x), y = p.y + t * dy;
    vec3 h = t.yzw - t.xyz;
    vec3 x0 = x.xyz, x1 = x.yzw, y0 = y.xyz, y1 = y.yzw;
    vec3 total = vec3(dot(h, x0 + x1) * 0.5,
                      dot(h, x0 * x0 + x0 * x1 + x1 * x1) / 6.0,
                      dot(h, 2.0 * x0 * y0 + x0 * y1 + x1 * y0 + 2.0 * x1 * y1) / 6.0);
    return dy * total;
}

// The integrals over the part of triangle (a, b, c) inside the unit pixel [0, 1]^2
// (pixel units relative to its lower-left corner) of 1 (returned: the covered area)
// and of the barycentric coordinates of b and c (`lambda`; that of a is the area
// minus both). A linear function with values fa, fb, fc at the corners integrates to
// fa (area - lambda.x - lambda.y) + fb lambda.x + fc lambda.y over the pixel, so the
// pixels' integrals sum to the triangle's, its area times (fa + fb + fc) / 3.
// `diagonal`: the edge a -> c's edge_moments relative to a, or (known = false)
// computed here where needed: the two triangles of a quad share its diagonal.
float pixel_integrals(vec2 a, vec2 b, vec2 c, inout vec3 diagonal, inout bool known,
                           out vec2 lambda) {
    lambda = vec2(0.0);
    vec2 u = b - a, w = c - a;
    float d = u.x * w.y - u.y * w.x;            // twice the signed area
    if (d == 0.0) return 0.0;
    float orientation = sign(d);
    vec2 lo = min(min(a, b), c), hi = max(max(a, b), c);
    float area;
    vec2 moment;                                // integral of (x - a) over the part
    if (all(greaterThanEqual(lo, vec2(0.0))) && all(lessThanEqual(hi, vec2(1.0)))) {
        area = 0.5 * abs(d);                    // the whole triangle
        moment = area * (u + w) / 3.0;
    } else {
        vec2 corners[3] = vec2[3](a, b, c);
        bool inside = true;
        for (int i = 0; i < 3; ++i) {
            vec2 p = corners[i], q = corners[i < 2 ? i + 1 : 0];
            vec2 e = orientation * vec2(p.y - q.y, q.x - p.x);   // inward normal
            float at0 = dot(e, -p);                             // at the corner (0, 0)
            float lowest = at0 + min(e.x, 0.0) + min(e.y, 0.0);
            float highest = at0 + max(e.x, 0.0) + max(e.y, 0.0);
            if (highest <= 0.0) return 0.0;                     // wholly outside this edge
            inside = inside && lowest >= 0.0;
        }
        if (inside) {
            area = 1.0;
            moment = vec2(0.5) - a;
        } else {
            // Relative to a, so the integrals scale with the triangle, not with its
            // place in the pixel (tiny triangles at a focus keep their precision).
            vec2 box_lo = -a, box_hi = vec2(1.0) - a;
            if (!known) {
                diagonal = edge_moments(vec2(0.0), w, box_lo, box_hi);
                known = true;
            }
            vec3 m = orientation * (edge_moments(vec2(0.0), u, box_lo, box_hi)
                                    + edge_moments(u, w, box_lo, box_hi) - diagonal);
            area = m.x;
            if (!(area > 0.0)) return 0.0;
            moment = m.yz;
        }
    }
    lambda = vec2(moment.x * w.y - moment.y * w.x, u.x * moment.y - u.y * moment.x) / d;
    return area;
}
