// The Gaussians program of a splat pass (splat_kernels.glsl: kernels `points` and
// `footprint`, and the quarters `triangles` cannot draw), included by
// caustic_splat.glsl and receiver_splat.glsl when TRIANGLES is not defined: a
// compute pass sets up one Gaussian per trace record that has one, then one vertex
// per such record draws it as a square point sprite over every target pixel the
// Gaussian's cut-off ellipse reaches, or, where the ellipse is long or leaning, as a
// rectangle along its axes (cutoff_box). With c the hit in target pixels, S the
// covariance (target pixels^2) and q = x - c for a pixel centre x, the pixel gets
//     w = exp(-q^T S^-1 q / 2)   where q^T S^-1 q <= u_cut^2 (else nothing),
//     rgb = value * w,  a = w,   value = share * flux / (norm * A):
// norm is the sum of w over the splat's pixels on the target (gaussian_norm), so the
// weights sum to one and the vertex's flux share is kept; A (m^2) is the receiver
// area of one target pixel at the hit, so rgb is irradiance (W/m^2).
// The set-up runs in four compute passes: FLAGS marks the records that have a
// Gaussian to draw (a hit on the target and a share left by the triangles), LIST
// lists them in record order (compact.glsl), the set-up proper runs over that list
// only, and COMPACT lists the listed ones drawn as rectangles. Listed first, the
// set-up's loops (its covariance's neighbours, the norm's pixels) run on a dense
// list instead of on one lane in eight (llvmpipe runs eight invocations in step;
// glass_sphere's grid has a Gaussian at 471 of its 16384 vertices), and the sprites'
// draw shades only the listed vertices; the same Gaussians blend in the same order,
// so the maps are the same bit for bit.
// The including pass defines, before including this file,
//   vec4 target_position(vec2 pix)     target pixels -> clip position
//   mat2 gaussian_covariance(int view, int tx, int ty, vec3 hit, vec3 normal, inout vec2 c)
//                                      S of the record of grid vertex (view, tx, ty),
//                                      hit P (m) with receiver normal `normal`, at
//                                      target pixel c (which it may move onto the
//                                      target)
//   void target_bounds(out vec2 lo, out vec2 hi)
//                                      the target's pixels [lo, hi) (one face of an
//                                      atlas)
//   vec3 gaussian_value(vec3 flux, float norm, vec3 hit, vec3 normal)
//                                      flux / (norm * A): `value` above
#if defined VERTEX_SHADER || defined COMPUTE_SHADER
// Each record's Gaussian (binding 5, three vec4 per record), set up by the compute
// pass (gaussian_setup below) and drawn by the vertex shader: the set-up's loops
// (the norm's pixels, the neighbours' hits) run on every thread the driver has,
// where llvmpipe shades a draw's vertices on one (glass_sphere, strong: caustic map
// 32 -> 29 ms on 2 cores; renders unchanged, bit for bit):
//   0: xy c (target pixels), z sprite size (pixels), w how it is drawn: 0 not,
//      1 as a sprite, 2 as a rectangle (BOXED)
//   1: S^-1 (target pixels^-2), columns xy and zw
//   2: rgb value (W/m^2 at weight 1), w 0
layout(std430, binding = 5) buffer GaussianSplats { vec4 gaussians[]; };
// The records drawn as rectangles, in record order (written by the COMPACT pass),
// and the indirect draw of them: 4 vertices (a strip) times their count.
layout(std430, binding = 6) buffer GaussianBoxes { int gaussian_boxes[]; };
layout(std430, binding = 7) buffer BoxesDraw { int boxes_draw[4]; };
// Per record, 1 where it has a Gaussian to set up (FLAGS); the listed records in
// record order (LIST); the set-up's dispatch over them (groups x, y, z and their
// count) and the sprites' draw of them (vertices, instances, first, base instance).
layout(std430, binding = 9) buffer GaussianFlags { int gaussian_flags[]; };
layout(std430, binding = 10) buffer GaussianList { int gaussian_list[]; };
layout(std430, binding = 11) buffer ListDispatch { uint list_dispatch[4]; };
layout(std430, binding = 12) buffer SpritesDraw { uint sprites_draw[4]; };

const int DRAWN_SPRITE = 1;
const int DRAWN_BOX = 2;
// Margin (pixels) for the rasteriser's fixed-point snapping of a rectangle's corners.
const float SNAP = 0.02;

// Half axes of the cut-off ellipse q^T M q <= cut^2 (M = S^-1, target pixels^-2):
// along M's eigenvectors e, of lengths cut / sqrt(eigenvalue), grown by SNAP. Every
// pixel centre within the ellipse lies in the rectangle c +- u +- w.
void cutoff_box(mat2 m, float cut, out vec2 u, out vec2 w) {
    float a = m[0][0], b = 0.5 * (m[0][1] + m[1][0]), d = m[1][1];
    float mid = 0.5 * (a + d), r = sqrt(0.25 * (a - d) * (a - d) + b * b);
    vec2 eigen = max(vec2(mid + r, mid - r), vec2(1.0e-30));
    // The eigenvector of the larger eigenvalue l, (l - d, b) or (b, l - a) from a
    // row of M - l I: the one that is not zero where b = 0.
    vec2 e = a >= d ? vec2(eigen.x - d, b) : vec2(b, eigen.x - a);
    e = dot(e, e) > 0.0 ? normalize(e) : vec2(1.0, 0.0);
    vec2 h = cut / sqrt(eigen) + SNAP;
    u = h.x * e;
    w = h.y * vec2(-e.y, e.x);
}
#endif

#if defined COMPUTE_SHADER
#if defined LIST || defined COMPACT
layout(local_size_x = 1024) in;
#include "compact.glsl"
#else
layout(local_size_x = 64) in;
#endif
uniform int u_count;            // records (invocations past it do nothing)

// Whether record i, grid vertex (view, tx, ty), has a Gaussian to draw: its hit in
// target pixels c, its share of the vertex's flux (the quarters of its quads the
// triangles do not draw).
bool gaussian_wanted(int i, out vec2 c, out float share, out int view, out int tx,
                     out int ty) {
    share = 0.0;
    record_vertex(i, view, tx, ty);
    if (!to_target(i, c)) return false;
    share = gaussian_share(view, tx, ty);
    return share > 0.0;
}

// The Gaussian of record i: false where it draws nothing (not splatted here, no
// share left by the triangles, or no pixel within its cut-off).
bool gaussian_setup(int i, out vec2 c, out mat2 inv, out vec3 value, out float size) {
    inv = mat2(1.0);
    value = vec3(0.0);
    size = 0.0;
    float share;
    int view, tx, ty;
    if (!gaussian_wanted(i, c, share, view, tx, ty)) return false;
    vec3 hit = splat_records[i * 5 + 2].xyz;
    vec3 normal = splat_records[i * 5 + 4].xyz;
    mat2 cov = gaussian_covariance(view, tx, ty, hit, normal, c);
    float radius = fit_radius(cov, u_cut, u_max_radius);
    inv = inverse(cov);
    vec2 lo, hi;
    target_bounds(lo, hi);
    float norm = gaussian_norm(c, inv, radius, u_cut, lo, hi);
    if (!(norm > 0.0)) return false;
    value = gaussian_value(share * splat_records[i * 5 + 3].rgb, norm, hit, normal);
    // The sprite covers the pixel centres within ceil(radius) of c: every texel the
    // cut-off ellipse reaches.
    size = 2.0 * ceil(radius) + 1.0;
    return true;
}

// A rectangle pays where it has at most half the sprite's pixels and at least
// BOX_SAVING fewer: its four vertices cost llvmpipe's single-threaded vertex stage
// more than a sprite's one (drawn as rectangles, the paper preset's round Gaussians
// made its caustic map 14 -> 19 ms on glass_sphere).
const float BOX_SAVING = 32.0;
int drawn_as(mat2 inv, float size) {
    if (u_tight_boxes == 0) return DRAWN_SPRITE;
    vec2 u, w;
    cutoff_box(inv, u_cut, u, w);
    float box = 4.0 * length(u) * length(w), sprite = size * size;
    return box <= 0.5 * sprite && sprite - box >= BOX_SAVING ? DRAWN_BOX : DRAWN_SPRITE;
}

#if defined FLAGS
void main() {
    int i = int(gl_GlobalInvocationID.x);
    if (i >= u_count) return;
    vec2 c;
    float share;
    int view, tx, ty;
    gaussian_flags[i] = gaussian_wanted(i, c, share, view, tx, ty) ? 1 : 0;
}
#elif defined LIST
bool compact_listed(int i) { return gaussian_flags[i] != 0; }
void compact_store(int slot, int i) { gaussian_list[slot] = i; }
void compact_total(int count) {
    list_dispatch = uint[4](uint((count + 63) / 64), 1u, 1u, uint(count));
    sprites_draw = uint[4](uint(count), 1u, 0u, 0u);
}

void main() { compact(u_count); }
#elif defined COMPACT
// The listed records drawn as rectangles, in record order (compact.glsl), so the
// rectangles blend in the same order on every run.
bool compact_listed(int slot) {
    return int(gaussians[gaussian_list[slot] * 3].w + 0.5) == DRAWN_BOX;
}
void compact_store(int slot, int listed) { gaussian_boxes[slot] = gaussian_list[listed]; }
void compact_total(int count) { boxes_draw = int[4](4, count, 0, 0); }

void main() { compact(int(list_dispatch[3])); }
#else
void main() {
    int slot = int(gl_GlobalInvocationID.x);
    if (slot >= int(list_dispatch[3])) return;
    int i = gaussian_list[slot];
    vec2 c;
    mat2 inv;
    vec3 value;
    float size;
    bool drawn = gaussian_setup(i, c, inv, value, size);
    gaussians[i * 3] = vec4(c, size, drawn ? float(drawn_as(inv, size)) : 0.0);
    gaussians[i * 3 + 1] = vec4(inv[0], inv[1]);
    gaussians[i * 3 + 2] = vec4(value, 0.0);
}
#endif
#elif defined VERTEX_SHADER
flat out vec3 v_value;       // W/m^2 at weight 1
flat out vec2 v_center;      // c (target pixels)
flat out mat2 v_inverse;     // S^-1 (target pixels^-2)
#if defined BOXED
// Instance k: the k-th boxed record; vertex j: corner c -+ u -+ w of its rectangle
// (a strip).
void main() {
    int i = gaussian_boxes[gl_InstanceID];
    vec4 head = gaussians[i * 3];
    vec4 inv = gaussians[i * 3 + 1];
    v_value = gaussians[i * 3 + 2].rgb;
    v_center = head.xy;
    v_inverse = mat2(inv.xy, inv.zw);
    vec2 u, w;
    cutoff_box(v_inverse, u_cut, u, w);
    vec2 corner = head.xy + ((gl_VertexID & 1) == 1 ? u : -u)
        + ((gl_VertexID & 2) == 2 ? w : -w);
    gl_Position = target_position(corner);
}
#else
// Vertex k: the k-th listed record.
void main() {
    int i = gaussian_list[gl_VertexID];
    vec4 head = gaussians[i * 3];
    vec4 inv = gaussians[i * 3 + 1];
    v_value = gaussians[i * 3 + 2].rgb;
    v_center = head.xy;
    v_inverse = mat2(inv.xy, inv.zw);
    gl_PointSize = max(head.z, 1.0);
    gl_Position = int(head.w + 0.5) == DRAWN_SPRITE ? target_position(head.xy)
                                                     : vec4(2.0, 2.0, 2.0, 1.0);   // culled
}
#endif
#elif defined FRAGMENT_SHADER
flat in vec3 v_value;
flat in vec2 v_center;
flat in mat2 v_inverse;
out vec4 out_irradiance;
void main() {
    vec2 q = gl_FragCoord.xy - v_center;
    float e = dot(q, v_inverse * q);                      // q^T S^-1 q
    if (e > u_cut * u_cut) discard;
    float w = exp(-0.5 * e);
    out_irradiance = vec4(v_value * w, w);
}
#endif
