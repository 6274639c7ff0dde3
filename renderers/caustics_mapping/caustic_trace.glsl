// Pass 3a: the vertex grid (paper Section 3.3). One invocation per object-atlas
// texel (invocation index -> view, texel). Each covered texel refracts or reflects
// the light, estimates where the ray meets the receivers from the receiver
// positions atlas, and writes one record; nothing is rasterised (the splat passes
// draw the records as point sprites). Run as a compute shader (COMPUTE_SHADER,
// u_count invocations: llvmpipe spreads compute work over its threads, vertex
// shading runs on one) or, identically, as a vertex shader over u_count points.
//
// Records (std430, binding 0), five vec4 per grid vertex:
//   0: xyz ray origin v (m), w object view index
//   1: xyz unit ray direction r, w estimated distance d (m)
//   2: xyz estimated hit P = v + d r (m), w status (STATUS_* in common.glsl)
//   3: rgb flux Phi (W; paper units in paper mode), w receiver index (-1: none)
//   4: xyz receiver normal at the hit, w |l . n| where the vertex reflects off a
//      conductor (light direction and shading normal; rim_patches.glsl patches the
//      quads near grazing), else -1
// History (binding 1): u_iterations + 1 floats per vertex, the estimate after
// 0, 1, ..., u_iterations updates (entry 0 is the start d_1 = g(0)); after a
// lost lookup or a divergence the last estimate is repeated. A reflected vertex whose
// estimate reflected_search() replaced keeps the estimator's history; its record holds
// the search's d.
//
// The estimators (estimators.glsl) find where the ray v + d r meets the receivers
// in the receiver positions atlas: T(x), the receiver position at x's light-space
// projection, is read nearest-texel or bilinear within one receiver (u_filtered,
// common.glsl); the exit surface likewise, at its own resolution u_back_size.
// u_start = 0 starts from d_1 = g(0) (the receiver seen along the light ray through
// the vertex), u_start = 1 from d_1 = u_start_distance (the appendix listing's start).
// Verified hits (u_verify): the final estimate P is accepted only if a receiver is
// seen at P and |T(P) - P| <= tolerance (u_hit_tolerance, or one positions-map texel
// at P's distance over |cos| between the light ray and the receiver normal, the
// cosine clamped at 0.1); otherwise the status is STATUS_UNCONVERGED and the vertex
// is splatted only with u_splat_unconverged. With verified hits a closed object's
// exit ray is also tested for re-entering its object (reenters()): the L T T D chain
// ends there, so such a vertex is STATUS_REENTERED and not splatted; so is a verified
// reflected ray that meets its object again before its hit (reflection_blocked()),
// and one that leaves below its own triangle (u_facet_side, below_own_triangle()).
//
// Rim patches (u_patches = 1): the records are those of the patches listed by
// rim_patches.glsl, (n + 1)^2 vertices per patch (n = u_front_stride), record
// (k * (n + 1) + j) * (n + 1) + i for vertex (i, j) of patch k: the quad's corners
// and the n - 1 points between them along each axis, at the centres of the front
// atlas's texels. The front atlas then has n texels per grid step (u_front_stride):
// the grid's own vertices read its texels n * t + (n - 1) / 2 (the same light rays
// as texel t of a grid-sized atlas), and so do the re-entry and reflection tests,
// so both traces see the surfaces at the grid's resolution but for the vertices'
// own first hits.
#include "common.glsl"

layout(std430, binding = 0) writeonly buffer Records { vec4 records[]; };
layout(std430, binding = 1) writeonly buffer History { float history[]; };
layout(std430, binding = 2) readonly buffer RimPatches { int patch_quads[]; };
// With u_patches: the patch vertices traced here (each shared vertex once, in its
// owner's patch; rim_patches.glsl) and their number (entry 3).
layout(std430, binding = 3) readonly buffer UniqueSlots { int unique_slots[]; };
layout(std430, binding = 4) readonly buffer UniqueDispatch { uint unique_dispatch[4]; };

uniform sampler2D u_receiver_positions;   // map atlas, RGBA32F (see common.glsl)
uniform sampler2D u_receiver_normals;
uniform int u_positions_size;
uniform sampler2D u_front_positions;      // object atlas, RGBA32F xyz, w object + 1
uniform sampler2D u_front_normals;
uniform sampler2D u_front_geometric;      // object atlas: the triangles' geometric normals
uniform sampler2D u_back_positions;      // object atlas at u_back_size texels per view
uniform sampler2D u_back_normals;
uniform sampler2D u_back_geometric;
uniform int u_depth_spread;               // 1: reflection_blocked and under_contact allow
                                          // for depth_spread (TraceOptions.depth_spread)
uniform int u_open_escape;                // 1: stays_in_front's escape (TraceOptions)
uniform int u_box_samples;                // 1: reflection_blocked samples within the box
uniform int u_shading_correction;         // 1: Veach's adjoint shading-normal factor
uniform int u_grid;
uniform int u_front_stride;     // front-atlas texels per grid step (odd)
uniform int u_patches;          // 1: the records are rim patches (see the header)
uniform int u_back_size;
uniform sampler2D u_far_positions;        // object atlas: the conductors' farthest surfaces
uniform sampler2D u_far_normals;
uniform int u_has_far;                    // 1: u_far_positions is bound
uniform mat4 u_obj_vp[6];
uniform int u_obj_cube;
uniform int u_obj_persp;
uniform vec4 u_obj_rect;        // x0, x1, y0, y1 of the object view (tangents or m)
uniform int u_filtered;         // 1: bilinear reads within one surface
uniform int u_start;            // 0 receiver (d1 = g(0)), 1 fixed (d1 = u_start_distance)
uniform float u_start_distance; // m
uniform int u_verify;           // 1: verified hits
uniform float u_hit_tolerance;  // m; <= 0: one positions-map texel (see header)

uniform int u_material[8];      // 0 none, 1 closed dielectric, 2 open dielectric, 3 conductor
uniform vec3 u_ior[8];
uniform vec3 u_absorption[8];   // K_a (1/m)
uniform vec3 u_reflectance[8];
uniform int u_fresnel[8];
uniform float u_extent[8];      // bounding-box diagonal (m): re-entry test length
uniform vec3 u_bound_lo[8];     // the object's axis-aligned bounding box (m)
uniform vec3 u_bound_hi[8];
uniform int u_convex[8];        // 1: a convex body, which no ray leaving it meets again
uniform int u_channel;          // -1: all channels; c: this pass carries channel c only

uniform int u_paper;            // 1: the paper's Eq. 6 flux, (N.L) / V
uniform float u_covered;        // V, grid texels covered (occlusion query)
uniform int u_estimator;        // 0 modified, 1 newton, 2 secant
uniform int u_safeguarded;
uniform int u_exit_iterations;  // refinements of the exit point (double refraction)

// The texel of an atlas with `stride` texels per step of a `size`-texel lattice per
// view that lies on the light ray through the lattice's texel t of view `face`.
ivec2 atlas_texel(int face, ivec2 t, int size, int stride) {
    return ivec2(face * size * stride, 0) + stride * t + (stride - 1) / 2;
}

const int REENTRY_STEPS = 48;   // samples of the exit ray over the object's extent
const float SHEET_STEPS = 8.0;     // reflection_blocked: a sheet's depth change per sample step
const float GRAZING = 0.3;       // reflection_blocked: |cos| below it is edge-on




#if defined COMPUTE_SHADER
layout(local_size_x = 64) in;
uniform int u_count;            // grid vertices (invocations past it do nothing)
#endif

#if defined VERTEX_SHADER || defined COMPUTE_SHADER

// T(x) and the unit receiver normal n there (receiver_lookup, common.glsl); false
// when no receiver is seen.
bool receiver_at(vec3 x, out vec4 t, out vec3 n) {
    return receiver_lookup(u_receiver_positions, u_receiver_normals, u_positions_size,
                           u_filtered == 1, x, t, n);
}

// T(x) beyond a receiver's edge (filtered lookups): where x's positions-atlas texel
// shows no receiver but one of the texels within EDGE_TEXELS of it (rings of growing
// Chebyshev radius, nearest first) does, T(x) is where the light ray through x meets
// that texel's tangent plane (position and normal), tagged with its receiver. A
// receiver ends between its last texel centre and the next, and a refracted ray
// near the edge starts from the light ray through the vertex, which may pass the
// edge by more than a texel (water_pool: 4.5 cm, the sun's slant minus the refracted
// ray's, over 1 m of water): without this those vertices were lost (2.1 % of the
// flux on water_pool). Only the estimates use it: the final hit must be seen at its
// own texel (verified hits), so a hit past the edge is not splatted, and one within
// the receiver's last half texel is lost with it (water_pool -0.2 %).
const int EDGE_TEXELS = 4;
bool receiver_beyond_edge(vec3 x, out vec4 t, out vec3 n) {
    t = vec4(0.0);
    n = vec3(0.0);
    int face = u_map_cube == 1 ? cube_face(x - u_light_pos) : 0;
    if (u_map_slot[face] < 0) return false;
    vec4 c = u_map_vp[face] * vec4(x, 1.0);
    if (!(c.w > 0.0)) return false;
    int size = u_positions_size;
    ivec2 centre = ivec2(floor((c.xy / c.w * 0.5 + 0.5) * float(size)));
    ivec2 base = ivec2(u_map_slot[face] * size, 0);
    vec3 l = incident_dir(x);
    for (int ring = 1; ring <= EDGE_TEXELS; ++ring) {
        float best = 1e30;
        // Only the ring's own 8 x ring texels, in row order (dy, then dx, rising):
        // its bottom row, the two ends of each middle row, its top row (scanning the
        // whole square and skipping its inside took twice the iterations; rim
        // patches on glass_sphere: 18 -> 13 ms a frame on llvmpipe).
        for (int i = 0; i < 8 * ring; ++i) {
            int dx, dy;
            if (i <= 2 * ring) {
                dx = i - ring;
                dy = -ring;
            } else if (i < 6 * ring - 1) {
                int j = i - 2 * ring - 1;
                dx = (j & 1) == 0 ? -ring : ring;
                dy = 1 - ring + (j >> 1);
            } else {
                dx = i - 7 * ring + 1;
                dy = ring;
            }
            ivec2 k = centre + ivec2(dx, dy);
            if (any(lessThan(k, ivec2(0))) || any(greaterThanEqual(k, ivec2(size)))) continue;
            vec4 p = texelFetch(u_receiver_positions, base + k, 0);
            if (p.w < 0.5) continue;
            vec3 m = texelFetch(u_receiver_normals, base + k, 0).xyz;
            float cos_l = dot(l, m);
            if (abs(cos_l) < 1e-3) continue;
            float s = dot(p.xyz - x, m) / cos_l;
            float dist = float(dx * dx + dy * dy);
            if (dist < best) {
                best = dist;
                t = vec4(x + s * l, p.w);
                n = m;
            }
        }
        if (best < 1e30) return true;
    }
    return false;
}

// T(x) and n (receiver_at), extrapolated past a receiver's edge with filtered lookups.
bool receiver_or_edge(vec3 x, out vec4 t, out vec3 n) {
    if (receiver_at(x, t, n)) return true;
    return u_filtered == 1 && receiver_beyond_edge(x, t, n);
}

// The estimators' surface 0 is the receiver positions atlas; each update's estimate
// goes to the vertex's history (its first float at `record`).
bool surface_at(int surface, vec3 x, out vec4 t) {
    vec3 n;
    return receiver_or_edge(x, t, n);
}

void estimate_record(int record, int k, float d) {
    history[record + k] = d;
}

// The estimators stop once |h| is at most u_converged positions-map texels at the
// estimate (estimators.glsl; 0: only at h = 0).
uniform float u_converged;
#define ESTIMATE_TOLERANCE(surface, x) (u_converged * map_texel_width(x, u_positions_size))

#include "estimators.glsl"

// The exit surface at x's projection into the object views (u_back_size texels per
// view): position p and unit normal n; false unless it is `object`'s.
bool back_at(vec3 x, int object, out vec3 p, out vec3 n) {
    int face = u_obj_cube == 1 ? cube_face(x - u_light_pos) : 0;
    vec2 ndc;
    p = vec3(0.0);
    n = vec3(0.0);
    if (!project(u_obj_vp[face], x, ndc)) return false;
    vec4 q;
    surface_read(u_back_positions, u_back_normals, face, u_back_size,
                 (ndc * 0.5 + 0.5) * float(u_back_size), u_filtered == 1, q, n);
    p = q.xyz;
    return abs(q.w - float(object + 1)) < 0.5;
}

// Veach's adjoint shading-normal factor (1997, Sec. 5.3) of a specular event that turns
// d into d2 at shading normal n and geometric normal ng,
//     |d . n| |d2 . ng| / (|d . ng| |d2 . n|),
// which the reference's photons carry so that light and camera tracing agree on meshes
// whose stored normals are interpolated (1 where n = ng); 0 for a direction in either
// tangent plane, as the reference drops it. Without u_shading_correction, or where the
// texel holds no geometric normal: 1 (flux conserved at the event, the paper's model).
float shading_factor(vec3 d, vec3 d2, vec3 n, vec3 ng) {
    if (u_shading_correction == 0 || dot(ng, ng) == 0.0) return 1.0;
    float den = abs(dot(d, ng)) * abs(dot(d2, n));
    return den > 0.0 ? abs(dot(d, n)) * abs(dot(d2, ng)) / den : 0.0;
}

// The geometric normal of the exit surface at x's projection (nearest texel; zero
// where x projects outside the views).
vec3 back_geometric_at(vec3 x) {
    int face = u_obj_cube == 1 ? cube_face(x - u_light_pos) : 0;
    vec2 ndc;
    vec4 q;
    vec3 g = vec3(0.0);
    if (project(u_obj_vp[face], x, ndc))
        surface_read(u_back_positions, u_back_geometric, face, u_back_size,
                     (ndc * 0.5 + 0.5) * float(u_back_size), false, q, g);
    return g;
}

// The exit point v + d r of the ray inside a closed object, and the exit normal bn.
// Wyman 2005: the back surface B is looked up in the back-surface texture. Start
// from the back surface along the light ray through v (his d_V) and refine along the
// refracted ray on e(d) = |B(v + d r) - v| - d: nearest reads take the fixed-point
// step d <- |B(v + d r) - v|; filtered reads take secant steps on e (the fixed-point
// step while no two points are known, or when a step leaves (0, 4 d)), which converge
// where the fixed point creeps (grazing exits). A filtered entry at the silhouette,
// where no back face lies along the light ray through v, steps 2, 4, 8, 16 back
// texels inside along r to find one.
bool find_exit(vec3 v, vec3 r, int object, out float d, out vec3 bn) {
    vec3 bp;
    d = 0.0;
    bool ok = back_at(v, object, bp, bn);
    if (!ok && u_filtered == 1) {
        float texel = max(u_obj_rect.y - u_obj_rect.x, u_obj_rect.w - u_obj_rect.z)
            / float(u_back_size) * (u_obj_persp == 1 ? length(v - u_light_pos) : 1.0);
        for (int k = 1; k <= 4 && !ok; ++k) ok = back_at(v + texel * exp2(float(k)) * r, object, bp, bn);
    }
    if (!ok) return false;
    d = length(bp - v);
    float d_prev = 0.0, e_prev = 0.0;
    bool have_prev = false;
    for (int k = 0; k < u_exit_iterations; ++k) {
        vec3 bq, bm;
        if (!back_at(v + d * r, object, bq, bm)) break;
        bn = bm;
        float fixed_point = length(bq - v);
        float e = fixed_point - d;
        float next = fixed_point;
        if (u_filtered == 1 && have_prev && e != e_prev) {
            float secant = d - e * (d - d_prev) / (e - e_prev);
            if (secant > 0.0 && secant < 4.0 * d) next = secant;
        }
        d_prev = d;
        e_prev = e;
        have_prev = true;
        if (next == d) break;
        d = next;
    }
    if (u_filtered == 1) {                    // the normal at the final estimate
        vec3 bq, bm;
        bool seen = back_at(v + d * r, object, bq, bm);
        if (seen) bn = bm;
        // Verified hits verify the exit too: an estimate whose own texel shows no exit
        // surface of the object has left it sideways (a refracted ray entering at the
        // silhouette, whose secant steps overshot): no exit was found, and its normal,
        // the last one seen, would refract it anywhere (dispersion_sphere, rim
        // patches: exits up to 2.3 R from the centre, 0.05 % of the flux, which total
        // internal reflection at that normal trapped).
        if (u_verify == 1 && !seen) return false;
    }
    return true;
}

// The first surface of `object` the light sees through x in an object atlas
// (`size` texels per view; nearest texel): its distance from the light along the
// light ray; false where that texel shows no surface of `object`.
bool surface_depth(sampler2D positions, int size, int stride, vec3 x, int object,
                   out float depth) {
    int face = u_obj_cube == 1 ? cube_face(x - u_light_pos) : 0;
    vec2 ndc;
    depth = 0.0;
    if (!project(u_obj_vp[face], x, ndc)) return false;
    ivec2 t = atlas_texel(face, min(ivec2(floor((ndc * 0.5 + 0.5) * float(size))),
                                    ivec2(size - 1)), size, stride);
    vec4 p = texelFetch(positions, t, 0);
    depth = light_distance(p.xyz);
    return abs(p.w - float(object + 1)) < 0.5;
}

// Whether the exit ray e + s r (s in (0, u_extent[object]]) enters `object` again,
// as far as the light's images of it show: a sample x of the ray lies inside the
// object's first slab seen from the light, behind its front surface and before its
// exit surface at x's texel by a quarter of an object-atlas texel width w at x (the
// slab's depths are read at texel centres), samples within 2 w of the exit point
// skipped (there the ray still crosses its own slab's rounded depths). On bunny
// (grid 128, strong) this drops 66 % of the flux whose exact exit ray meets an
// object; 3.5 % of what it drops has an exact path to the floor. Entries behind the
// first slab (a second layer under an overhang, which neither image shows) are not
// seen.
// Samples past the object's bounding box, grown by one front-atlas texel width at
// its farthest point from the light, are not taken: they cannot pass. A sample x
// passes only with its light distance between the front and the exit surfaces'
// depths read through x's texels, whose light rays run within half a texel width
// of x; the points of those surfaces lie in the box, and so, at x's depth, does a
// point of the segment between them, within half a texel width of x (x farther from
// the light than the box fails the exit surface's depth). So the test's outcome is
// the same, at about a sixth of the samples on the bunny's exit rays (bunny strong:
// trace 15.6 -> 9.3 ms on llvmpipe; records unchanged).
// Where (m along r) the ray e + s r leaves `object`'s bounding box grown by one
// object-atlas texel width at its farthest point from the light (`view`: the object
// view's larger extent).
float box_exit(vec3 e, vec3 r, int object, float view) {
    vec3 lo = u_bound_lo[object], hi = u_bound_hi[object];
    float far = u_obj_persp == 1 ? length(0.5 * (lo + hi) - u_light_pos) + 0.5 * length(hi - lo)
                                 : 1.0;
    vec3 grown = vec3(view / float(u_grid) * far);
    vec3 t1 = (lo - grown - e) / r, t2 = (hi + grown - e) / r;   // +-inf where r's axis is 0
    vec3 leave = max(t1, t2);
    return min(min(leave.x, leave.y), leave.z);
}

int reentry_samples(vec3 e, vec3 r, int object, float len, float view) {
    float t = box_exit(e, r, object, view);
    return int(clamp(floor(t / len * float(REENTRY_STEPS)), 0.0, float(REENTRY_STEPS)));
}

bool reenters(vec3 e, vec3 r, int object) {
    float len = u_extent[object];
    if (!(len > 0.0)) return false;
    float view = max(u_obj_rect.y - u_obj_rect.x, u_obj_rect.w - u_obj_rect.z);
    int samples = reentry_samples(e, r, object, len, view);
    for (int k = 1; k <= samples; ++k) {
        vec3 x = e + (len * float(k) / float(REENTRY_STEPS)) * r;
        float margin = view / float(u_grid) * (u_obj_persp == 1 ? length(x - u_light_pos) : 1.0);
        if (length(x - e) < 2.0 * margin) continue;
        float front, back, dx = light_distance(x);
        if (!surface_depth(u_front_positions, u_grid, u_front_stride, x, object, front))
            continue;
        if (dx < front + 0.25 * margin) continue;
        if (surface_depth(u_back_positions, u_back_size, 1, x, object, back)
            && dx < back - 0.25 * margin)
            return true;
    }
    return false;
}

// How far (m) a surface seen through a texel may lie from the light, nearer or
// farther than the texel centre's point, at a point within that texel: its depth
// change over half the texel's diagonal plus a quarter texel for rounding,
// w (0.7071 tan(theta) + 0.25), w the texel width there, theta the angle between the
// surface normal and the light (c = |cos theta|). A sample whose depth differs from
// the texel's point by less cannot be told in front of the surface or behind it.
float depth_spread(float c, float w) {
    return w * (0.7071 * sqrt(max(1.0 - c * c, 0.0)) / max(c, 1e-3) + 0.25);
}

// One layer of a reflection_blocked test: the sample x's side of the layer's surface
// seen through its texel (nearest), and whether the ray crossed that surface since
// the last sample that saw it (`s_prev`, `f_prev`, `n_prev`: its side, the surface
// point and normal seen; `have_prev`: whether there is one). `edge`: a
// sample whose texel shows no object, after one behind an edge-on sheet (|cos| to the
// light below GRAZING), left through that sheet (see reflection_blocked); `last`: the
// normal and side of the last sample that saw the layer, zero after one that saw
// none. With u_depth_spread, a sample behind the surface by no more than its
// depth_spread is not taken as behind it, nor as a crossing (`hit`: the sample is the
// ray's hit itself, which is taken whatever its depth).
bool crosses_layer(sampler2D positions, sampler2D normals, int stride, bool edge, bool hit,
                   vec3 x, int object, float step, float w, inout float s_prev,
                   inout vec3 f_prev, inout vec3 n_prev, inout bool have_prev,
                   inout vec4 last) {
    int face = u_obj_cube == 1 ? cube_face(x - u_light_pos) : 0;
    vec2 ndc;
    vec4 f = vec4(0.0);
    ivec2 t = ivec2(0);
    if (project(u_obj_vp[face], x, ndc)) {
        t = atlas_texel(face, min(ivec2(floor((ndc * 0.5 + 0.5) * float(u_grid))),
                                  ivec2(u_grid - 1)), u_grid, stride);
        f = texelFetch(positions, t, 0);
    }
    if (abs(f.w - float(object + 1)) >= 0.5) {
        bool left = edge && dot(last.xyz, last.xyz) > 0.0 && last.w > 0.0
            && abs(dot(last.xyz, incident_dir(x))) < GRAZING;
        have_prev = false;
        last = vec4(0.0);
        return left;
    }
    vec3 n = texelFetch(normals, t, 0).xyz;
    float s = light_distance(x) - light_distance(f.xyz);   // > 0: behind it from the light
    last = vec4(n, s);
    // Where the ray runs within a texel of a sheet, behind it by less than the
    // sheet's depth spread, the texel's point may lie either side of the ray: such a
    // sample leaves the side last taken as it was. A sheet seen nearly edge-on
    // spreads over centimetres in a texel, and grazing reflections leaving a bowl's
    // convex outer wall run along it within a texel of the light's silhouette,
    // reading a millimetre behind one texel's point and well in front of the next
    // one's (1.0 % of bowl_deep_sun75's floor flux was ended so, their exact rays
    // reaching the floor; a rule on the ray's direction through the sheet, which
    // this leaves nothing to do, is gone). The hit is taken as read: a ray that
    // meets the object within a texel of the receiver (a bowl's bottom on the floor)
    // shows its crossing only there.
    if (u_depth_spread == 1 && !hit && s > 0.0
        && s <= depth_spread(abs(dot(n, incident_dir(f.xyz))), w))
        return false;
    bool crossed = have_prev && (s > 0.0) != (s_prev > 0.0) && dot(n, n_prev) > 0.5
        && abs(dot(f.xyz - f_prev, n_prev)) <= SHEET_STEPS * step + 2.0 * w;
    s_prev = s;
    f_prev = f.xyz;
    n_prev = n;
    have_prev = true;
    return crossed;
}

// Whether the reflected ray v + s r meets `object` again before the estimate s = d,
// as far as the light's two images of the objects show: the front (nearest) surfaces
// and, where bound, the conductors' farthest ones (u_far_positions; nearest texel). A
// ray crossing a surface an image shows passes from in front of it (nearer the light
// than the surface seen through the sample's texel) to behind it, or back, between
// two samples that see one sheet: normals within 60 deg, and the second surface point
// within SHEET_STEPS sample steps plus 2 texel widths w of the first one's tangent
// plane (else the view passed an edge to another sheet, e.g. from the far wall of a
// ring, normal towards the light, to the near one, normal away from it, which
// crosses nothing; measured off the tangent plane, not along the light ray, so that
// a sheet seen edge-on, whose depth jumps from texel to texel, stays one sheet).
// A sheet seen edge-on from the light (a cup's side walls) shows in neither image
// where the ray crosses it, and the ray's next samples lie outside the objects'
// silhouette: with `edge` (the reflection itself not grazing, |cos| above GRAZING), a
// ray behind an edge-on front sheet whose next sample sees no object has crossed it.
// (A grazing reflection runs along its sheet, behind it by the texels' rounding, and
// leaves the silhouette without crossing anything: bowl_sun's rim.)
// REENTRY_STEPS samples up to the hit itself, or with u_box_samples up to where the
// ray leaves the object's bounding box grown by a texel if that comes first (past it
// no surface of the object is seen; spread over a 7 m ray the samples were 14 cm
// apart and missed crossings near the outline: bowl_shallow_sun60's rim); those
// within 2 w of v are skipped (the
// ray still leaves its own sheet's rounded depths). The chain L S D ends at the
// object, as the reference's does: 19 % of cup_sun's splatted flux, 52 % of
// bowl_sun's, came from rays that meet the object again. Against exact ray casts of
// the same rays (grid 128, strong), what is splatted and what reaches the floor
// differ by +0.7 % (cup_sun), -0.05 % (bowl_sun), +0.08 % (ring_point) and -0.02 %
// (metal_ring).
bool reflection_blocked(vec3 v, vec3 r, float d, int object, bool edge) {
    float view = max(u_obj_rect.y - u_obj_rect.x, u_obj_rect.w - u_obj_rect.z);
    float len = u_box_samples == 1 ? min(d, box_exit(v, r, object, view)) : d;
    float step = len / float(REENTRY_STEPS);  // the last sample is the hit, or leaves the box
    float s_front = 0.0, s_far = 0.0;
    vec3 f_front = vec3(0.0), n_front = vec3(0.0), f_far = vec3(0.0), n_far = vec3(0.0);
    vec4 last_front = vec4(0.0), last_far = vec4(0.0);
    bool have_front = false, have_far = false;
    for (int k = 1; k <= REENTRY_STEPS; ++k) {
        vec3 x = v + (step * float(k)) * r;
        float w = view / float(u_grid) * (u_obj_persp == 1 ? length(x - u_light_pos) : 1.0);
        if (step * float(k) < 2.0 * w) continue;
        bool hit = k == REENTRY_STEPS && len == d;
        if (crosses_layer(u_front_positions, u_front_normals, u_front_stride, edge, hit, x,
                          object, step, w, s_front, f_front, n_front, have_front, last_front))
            return true;
        if (u_has_far == 1 && crosses_layer(u_far_positions, u_far_normals, 1, false, hit, x,
                                            object, step, w, s_far, f_far, n_far, have_far,
                                            last_far))
            return true;
    }
    return false;
}

// The receiver search for a reflected ray that the estimator left unverified
// (u_reflected_search; verified hits). The estimators solve h(d) = g(d) - d = 0 with
// g(d) = |T(P(d)) - v|, a root where h changes sign when the ray runs on with the
// light (beyond the hit, T(P(d)) lies back towards the light from P(d): g < d). A ray
// reflected back towards the light does not: beyond the hit T(P(d)) lies farther
// from v than P(d), so g(d) >= d on both sides and h only touches 0 there (a bowl's
// sun-facing outside under a low sun: the secant and its bracket run away from the
// hit). This search solves instead for the signed depth along the light,
//   sigma(d) = L(T(P(d))) - L(P(d))   (L: light_distance; m),
// > 0 while P(d) is nearer the light than the receiver seen through it, < 0 behind it:
// sigma changes sign where the ray meets the receiver, whichever way the ray runs. It
// starts from the tangent plane of the receiver seen through v, T(v) with normal m:
// d_1 = (T(v) - v) . m / -(r . m), the hit itself on a flat receiver under a
// directional light, where sigma is linear in d; while sigma(d_1) > 0 (the receiver
// falls away) the far end doubles, at most REFLECTED_MARCH times; then false position
// with the Illinois halving on the bracket [lo, hi] (sigma(lo) > 0 >= sigma(hi)), at
// most REFLECTED_STEPS updates, stopping at |sigma| within the estimators' tolerance
// (u_converged positions texels). False where the ray leaves that tangent plane (v
// and v + r on one side of it) or a probe sees no receiver: the vertex stays
// unconverged. The caller verifies the result as any estimate.
const int REFLECTED_MARCH = 4;
const int REFLECTED_STEPS = 8;
uniform int u_reflected_search;     // 1: reflected_search() after an unverified estimate
uniform int u_contact_test;         // 1: a reflected hit under a contact ends (under_contact)
uniform int u_facet_side;           // 1: a reflection below its own triangle ends (reentered)

bool depth_gap(vec3 x, out float sigma) {
    vec4 t;
    vec3 m;
    sigma = 0.0;
    if (!receiver_or_edge(x, t, m)) return false;
    sigma = light_distance(t.xyz) - light_distance(x);
    return true;
}

bool reflected_search(vec3 v, vec3 r, out float d) {
    d = 0.0;
    vec4 t0;
    vec3 m;
    if (!receiver_or_edge(v, t0, m)) return false;
    float above = dot(v - t0.xyz, m), approach = -dot(r, m);
    float s_lo = light_distance(t0.xyz) - light_distance(v);
    if (!(above > 0.0) || !(approach > 0.0) || !(s_lo > 0.0)) return false;
    float lo = 0.0, hi = above / approach, s_hi = 0.0;
    bool bracketed = false;
    for (int k = 0; k < REFLECTED_MARCH && !bracketed; ++k) {
        if (!depth_gap(v + hi * r, s_hi)) return false;
        if (abs(s_hi) <= ESTIMATE_TOLERANCE(0, v + hi * r)) { d = hi; return true; }
        if (s_hi < 0.0) {
            bracketed = true;
        } else {
            lo = hi;
            s_lo = s_hi;
            hi *= 2.0;
        }
    }
    if (!bracketed) return false;
    int side = 0;                    // the end kept last time: +1 lo, -1 hi
    for (int k = 0; k < REFLECTED_STEPS; ++k) {
        d = lo + s_lo * (hi - lo) / (s_lo - s_hi);    // inside (lo, hi): s_lo > 0 > s_hi
        float s;
        if (!depth_gap(v + d * r, s)) return false;
        if (abs(s) <= ESTIMATE_TOLERANCE(0, v + d * r)) return true;
        if (s > 0.0) {
            lo = d;
            s_lo = s;
            if (side == 1) s_hi *= 0.5;       // Illinois: the stale end's value halved
            side = 1;
        } else {
            hi = d;
            s_hi = s;
            if (side == -1) s_lo *= 0.5;
            side = -1;
        }
    }
    d = lo + s_lo * (hi - lo) / (s_lo - s_hi);
    return true;
}

// Whether the ray v + s r, s in (0, d], stays in front of every object surface the
// light sees (u_front_positions, nearest texel), as far as that image shows: no
// sample farther from the light than the front surface f seen through its texel by
// more than that surface's depth spread over half a texel plus a quarter texel,
// w (0.5 tan(theta) + 0.25) with w the texel width at the sample and theta the angle
// between the surface normal and the light (tan capped at 10). The samples,
// FRONT_STEPS of them, cover only the part of the ray inside the object's bounding
// box grown by a texel (past it no surface of the object is seen: reentry_samples'
// argument), those within 2 w of v skipped (the ray still leaves its own sheet's
// rounded depths). A stricter test than reflection_blocked, for the hits of
// reflected_search only: those rays run back towards the light, and where one
// crosses a sheet that the light sees edge-on (a bowl's side wall, from its far inside
// wall) neither image shows the crossing, so reflection_blocked let them through
// (bowl_sun: flux ratio 1.05 with them). A ray that passes behind a surface the light
// sees without meeting it (under a bowl's rim seen from the light) fails the test too
// and stays unconverged: measured in the flux budget's "estimator failed" share.
// With u_open_escape, a ray behind a sheet the light does not see edge-on (|cos| at
// least GRAZING) that then leaves the objects' silhouette, or their bounding box,
// before it comes back in front has left through an opening, as through a
// half-pipe's open end under its near wall's shadow (halfpipe_sun20: 1.6 % of the
// floor's flux, all of it from the far inside wall). Behind an edge-on sheet, or
// back in front within the box, the ray may have crossed it and fails as before.
const int FRONT_STEPS = 96;
bool stays_in_front(vec3 v, vec3 r, float d, int object) {
    float view = max(u_obj_rect.y - u_obj_rect.x, u_obj_rect.w - u_obj_rect.z);
    float len = min(d, float(reentry_samples(v, r, object, d, view)) / float(REENTRY_STEPS) * d
                       + d / float(REENTRY_STEPS));
    float step = len / float(FRONT_STEPS);
    bool behind = false, seen = false, outside = false;
    float behind_cos = 0.0;
    vec3 f_prev = vec3(0.0), n_prev = vec3(0.0);   // the last in-front sample's surface
    for (int k = 1; k <= FRONT_STEPS; ++k) {
        vec3 x = v + (step * float(k)) * r;
        float w = view / float(u_grid) * (u_obj_persp == 1 ? length(x - u_light_pos) : 1.0);
        if (step * float(k) < 2.0 * w) continue;
        int face = u_obj_cube == 1 ? cube_face(x - u_light_pos) : 0;
        vec2 ndc;
        vec4 f = vec4(0.0);
        ivec2 t = ivec2(0);
        if (project(u_obj_vp[face], x, ndc) && all(lessThanEqual(abs(ndc), vec2(1.0)))) {
            t = atlas_texel(face, min(ivec2(floor((ndc * 0.5 + 0.5) * float(u_grid))),
                                      ivec2(u_grid - 1)), u_grid, u_front_stride);
            f = texelFetch(u_front_positions, t, 0);
        }
        if (f.w < 0.5) {                // off the silhouette: left it, or failed
            if (behind && behind_cos < GRAZING) return false;
            behind = seen = false;
            outside = true;
            continue;
        }
        vec3 n = texelFetch(u_front_normals, t, 0).xyz;
        float c = abs(dot(n, incident_dir(x)));
        float slope = min(sqrt(max(1.0 - c * c, 0.0)) / max(c, 1e-3), 10.0);
        bool back = light_distance(x) > light_distance(f.xyz) + w * (0.5 * slope + 0.25);
        if (back && u_open_escape == 0) return false;
        if (!back && behind) return false;
        // Behind from the first sample, or from in front of the same sheet (as
        // reflection_blocked tells one sheet: normals within 60 deg, the point within
        // SHEET_STEPS steps plus 2 texels of the tangent plane): through it. Only
        // passing under an edge of the image, from off the silhouette or from a
        // farther sheet to one nearer the light, is not.
        if (back && !behind && !outside && (!seen || (dot(n, n_prev) > 0.5
                && abs(dot(f.xyz - f_prev, n_prev)) <= SHEET_STEPS * step + 2.0 * w)))
            return false;
        if (back) {
            behind = true;
            behind_cos = c;
        } else {
            seen = true;
            f_prev = f.xyz;
            n_prev = n;
        }
        outside = false;
    }
    // Still behind at the last sample: through the box's side when the samples stopped
    // short of the hit (len < d), as above.
    return !behind || (behind_cos >= GRAZING && len < d);
}

// Whether the hit p on a receiver of normal `normal` lies where `object` rests on the
// receiver: the front atlas (nearest texel, the grid's resolution) shows the object
// at p's texel, its surface within 30 deg of parallel to the receiver, and the
// surface's tangent plane there meets the light ray through p within a quarter texel
// width w of p (the plane carries the texel centre's point over to p's own light ray,
// exactly on a flat facet), or with u_depth_spread within the surface's depth_spread
// (the tangent plane of a curved bottom strays from it by that much across a texel).
// Light cannot reach such a point but through the object: a bowl's bottom on the
// floor, where reflections off the inside meet the bowl within millimetres of the
// floor, closer than the object images resolve (reflection_blocked sees no crossing
// there; with its depth spread, none a few centimetres out from the contact either:
// bowl_shallow_sun45, 0.5 % of the floor's flux splatted so with the quarter texel).
bool under_contact(vec3 p, vec3 normal, int object) {
    int face = u_obj_cube == 1 ? cube_face(p - u_light_pos) : 0;
    vec2 ndc;
    if (!project(u_obj_vp[face], p, ndc) || any(greaterThan(abs(ndc), vec2(1.0)))) return false;
    ivec2 t = atlas_texel(face, min(ivec2(floor((ndc * 0.5 + 0.5) * float(u_grid))),
                                    ivec2(u_grid - 1)), u_grid, u_front_stride);
    vec4 f = texelFetch(u_front_positions, t, 0);
    if (abs(f.w - float(object + 1)) >= 0.5) return false;
    vec3 m = texelFetch(u_front_normals, t, 0).xyz;
    if (abs(dot(m, normal)) < 0.866) return false;
    vec3 l = incident_dir(p);
    float c = dot(l, m);
    if (abs(c) < 1e-3) return false;
    float gap = dot(p - f.xyz, m) / c;        // from the plane to p along the light ray (m)
    float view = max(u_obj_rect.y - u_obj_rect.x, u_obj_rect.w - u_obj_rect.z);
    float w = view / float(u_grid) * (u_obj_persp == 1 ? length(p - u_light_pos) : 1.0);
    return abs(gap) <= (u_depth_spread == 1 ? depth_spread(abs(c), w) : 0.25 * w);
}

// The status of the estimate d on the ray v + d r (n: the surface normal at v, facing
// the light): STATUS_HIT, or with verified hits STATUS_UNCONVERGED or
// STATUS_REENTERED; without, STATUS_LOST where no receiver is seen at the estimate.
// `receiver` (index, -1 none) and `normal`: the receiver seen at the estimate.
int verify_hit(vec3 v, vec3 r, vec3 n, float d, int material, int object,
               out float receiver, out vec3 normal) {
    vec3 p = v + d * r;
    int status = STATUS_HIT;
    receiver = -1.0;
    normal = vec3(0.0);
    vec4 t;
    vec3 n_seen;
    bool seen = receiver_at(p, t, n_seen);
    if (seen) {
        receiver = t.w - 1.0;
        normal = n_seen;
    }
    if (u_verify == 1) {
        float tol = u_hit_tolerance;
        if (tol <= 0.0) {
            float c = seen ? abs(dot(normal, incident_dir(p))) : 1.0;
            tol = map_texel_width(p, u_positions_size) / max(c, 0.1);
        }
        if (!seen || length(t.xyz - p) > tol) status = STATUS_UNCONVERGED;
        // A reflected ray leaving the receiver's tangent plane at T(P) (v and v + r
        // on the same side) cannot meet it: an estimate within the tolerance of it
        // is a ray from an object that touches the receiver (bowl_sun's bottom,
        // within a texel of the floor, reflecting upwards: 1.4 % of its flux).
        else if (material == 3 && dot(r, normal) * dot(v - t.xyz, normal) >= 0.0)
            status = STATUS_UNCONVERGED;
        // A hit where the object rests on the receiver is reached only through it.
        else if (material == 3 && u_convex[object] == 0 && u_contact_test == 1
                 && under_contact(p, normal, object))
            status = STATUS_REENTERED;
        // Sampled up to the receiver's tangent plane at T(P), past P where P stops
        // short of it within the tolerance: a ray that meets the object within a
        // texel of the receiver (bowl_sun's bottom, 1.3 % of its flux, all in one
        // spot under the bowl) crosses it only there.
        else if (material == 3 && u_convex[object] == 0
                 && reflection_blocked(v, r, max(d, dot(t.xyz - v, normal) / dot(r, normal)),
                                       object, abs(dot(r, n)) > GRAZING))
            status = STATUS_REENTERED;
    } else if (!seen) {
        status = STATUS_LOST;
    }
    return status;
}

// |l . n| of this invocation's reflection off a conductor, -1 where it has none
// (record 4's w).
float g_reflection_cos = -1.0;

// Whether the reflected ray r of the light l leaves on the far side of the plane of its
// own triangle (geometric normal ng; zero: unknown, false): near grazing the shading
// normal can tilt the reflection past the facet, which the reference's photon then
// crosses, meeting its object again (an L R R chain it does not count). On the
// concave family's outer walls (grid 128) the vertices this ends carried 1.2 % of
// bowl_deep_sun75's floor flux and 0.69 % of bowl_shallow_sun45's, reflected within
// 1 deg of grazing; the exact rays of all but 0.09 % of deep75's floor flux meet the
// bowl again, most within 0.5 to 3 cm: below the resolution of reflection_blocked()'s
// samples.
bool below_own_triangle(vec3 l, vec3 r, vec3 ng) {
    return dot(r, ng) * dot(l, ng) > 0.0;   // -l and r on opposite sides of the plane
}

void write_record(int base, vec3 v, float view, vec3 r, float d, vec3 p, int status,
                  vec3 flux, float receiver, vec3 normal) {
    records[base + 0] = vec4(v, view);
    records[base + 1] = vec4(r, d);
    records[base + 2] = vec4(p, float(status));
    records[base + 3] = vec4(flux, receiver);
    records[base + 4] = vec4(normal, g_reflection_cos);
}

void main() {
#if defined COMPUTE_SHADER
    int id = int(gl_GlobalInvocationID.x);
    if (u_patches == 1) {
        if (id >= int(unique_dispatch[3])) return;
        id = unique_slots[id];
    } else if (id >= u_count) {
        return;
    }
#else
    gl_Position = vec4(2.0, 2.0, 2.0, 1.0);    // clipped: this pass rasterises nothing
    gl_PointSize = 1.0;
    int id = gl_VertexID;
#endif
    // The vertex's view and its front-atlas texel `at` within the view; `cells`
    // texels per view of the vertex lattice (its flux is one such texel's).
    int view, cells;
    ivec2 at;
    vec2 ndc;
    int stride = u_front_stride;
    if (u_patches == 1) {
        int side = stride + 1, quads = u_grid - 1;
        int k = id / (side * side), local = id - k * side * side;
        int q = patch_quads[k];
        view = q / (quads * quads);
        int within = q - view * quads * quads;
        at = stride * ivec2(within % quads, within / quads) + (stride - 1) / 2
            + ivec2(local % side, local / side);
        cells = u_grid * stride;
        ndc = (vec2(at) + 0.5) / float(cells) * 2.0 - 1.0;
    } else {
        int per_view = u_grid * u_grid;
        view = id / per_view;
        int local = id - view * per_view;
        ivec2 t = ivec2(local % u_grid, local / u_grid);
        at = stride * t + (stride - 1) / 2;
        cells = u_grid;
        ndc = (vec2(t) + 0.5) / float(u_grid) * 2.0 - 1.0;
    }
    int base = id * 5;
    int hbase = id * (u_iterations + 1);
    ivec2 a = ivec2(view * u_grid * stride, 0) + at;
    vec4 fp = texelFetch(u_front_positions, a, 0);
    int object = int(fp.w + 0.5) - 1;
    if (object < 0 || u_material[object] == 0) {
        for (int k = 0; k <= u_iterations; ++k) history[hbase + k] = 0.0;
        write_record(base, vec3(0.0), float(view), vec3(0.0), 0.0, vec3(0.0), STATUS_EMPTY,
                     vec3(0.0), -1.0, vec3(0.0));
        return;
    }
    vec3 v = fp.xyz;
    vec3 l = incident_dir(v);
    vec3 n = texelFetch(u_front_normals, a, 0).xyz;
    if (dot(n, l) > 0.0) n = -n;               // face the light (two-sided surfaces)

    // Flux carried by this grid texel (radiometric contract, docs/method.md): I * the
    // texel's solid angle (point, spot) or E0 * its area across the beam
    // (directional); or the paper's Eq. 6, (N . L) / V in units of the light's power.
    vec3 flux;
    if (u_paper == 1) {
        flux = u_light_power * max(dot(n, -l), 0.0) / max(u_covered, 1.0);
    } else {
        flux = u_light_power * light_falloff(l) * texel_measure(u_obj_persp, u_obj_rect, cells, ndc);
    }
    vec3 mask = u_channel < 0 ? vec3(1.0) : vec3(equal(ivec3(0, 1, 2), ivec3(u_channel)));
    flux *= mask;
    float ior = u_channel < 0 ? u_ior[object].x : u_ior[object][u_channel];
    int material = u_material[object];
    bool fresnel = u_fresnel[object] == 1;

    vec3 r;
    float inside = 0.0;                         // path length in the medium (m)
    if (material == 3) {
        r = reflect(l, n);
        g_reflection_cos = abs(dot(l, n));
        flux *= u_reflectance[object];
    } else {
        r = refract(l, n, 1.0 / ior);
        if (fresnel) flux *= fresnel_transmittance(-dot(l, n), 1.0, ior);
    }
    vec3 ng = texelFetch(u_front_geometric, a, 0).xyz;
    if (dot(r, r) > 0.0) flux *= shading_factor(l, r, n, ng);
    if (u_facet_side == 1 && material == 3 && below_own_triangle(l, r, ng)) {
        for (int k = 0; k <= u_iterations; ++k) history[hbase + k] = 0.0;
        write_record(base, v, float(view), r, 0.0, v, STATUS_REENTERED, flux, -1.0, vec3(0.0));
        return;
    }
    if (material == 1) {
        float d;
        vec3 bn;
        if (!find_exit(v, r, object, d, bn)) {
            for (int k = 0; k <= u_iterations; ++k) history[hbase + k] = 0.0;
            write_record(base, v, float(view), r, 0.0, v, STATUS_NO_EXIT, flux, -1.0, vec3(0.0));
            return;
        }
        inside = d;
        vec3 exit_point = v + d * r;
        vec3 m = dot(r, bn) > 0.0 ? -bn : bn;   // exit normal facing the inside ray
        vec3 r2 = refract(r, m, ior);
        if (fresnel) flux *= fresnel_transmittance(-dot(r, m), ior, 1.0);
        if (dot(r2, r2) > 0.0) flux *= shading_factor(r, r2, m, back_geometric_at(exit_point));
        if (dot(r2, r2) == 0.0) {
            for (int k = 0; k <= u_iterations; ++k) history[hbase + k] = 0.0;
            write_record(base, exit_point, float(view), r, 0.0, exit_point, STATUS_TIR, flux,
                         -1.0, vec3(0.0));
            return;
        }
        v = exit_point;
        r = r2;
        flux *= exp(-u_absorption[object] * inside);  // Eq. 7 inside the solid
        if (u_verify == 1 && u_convex[object] == 0 && reenters(v, r, object)) {
            for (int k = 0; k <= u_iterations; ++k) history[hbase + k] = 0.0;
            write_record(base, v, float(view), r, 0.0, v, STATUS_REENTERED, flux, -1.0,
                         vec3(0.0));
            return;
        }
    }

    float d, d_seen;
    int status = estimate_along(0, v, r, u_start == 1 ? u_start_distance : -1.0, u_estimator,
                                u_safeguarded == 1, hbase, d, d_seen);
    vec3 p = v + d * r;
    float receiver = -1.0;
    vec3 normal = vec3(0.0);
    if (status == STATUS_HIT) status = verify_hit(v, r, n, d, material, object, receiver, normal);
    // A reflected ray left unverified gets the signed-depth search (reflected_search);
    // its estimate replaces the first only where it is verified, so every vertex the
    // estimator verified keeps its record bit for bit.
    if (u_reflected_search == 1 && material == 3 && status == STATUS_UNCONVERGED) {
        float d2;
        if (reflected_search(v, r, d2)) {
            float receiver2;
            vec3 normal2;
            int status2 = verify_hit(v, r, n, d2, material, object, receiver2, normal2);
            if (status2 == STATUS_HIT && !stays_in_front(v, r, d2, object))
                status2 = STATUS_UNCONVERGED;
            if (status2 != STATUS_UNCONVERGED) {
                d = d2;
                p = v + d * r;
                status = status2;
                receiver = receiver2;
                normal = normal2;
            }
        }
    }
    // Eq. 7 for a water surface: attenuation from the surface to the receiver.
    if (material == 2) flux *= exp(-u_absorption[object] * max(d, 0.0));
    write_record(base, v, float(view), r, d, p, status, flux, receiver, normal);
}

#elif defined FRAGMENT_SHADER
out vec4 out_color;
void main() { out_color = vec4(0.0); }
#endif
