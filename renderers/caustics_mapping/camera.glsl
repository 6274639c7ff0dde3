// Pass 5: the final camera pass (paper Section 3.2). Output RGBA32F: rgb linear
// radiance (W m^-2 sr^-1), a = 1 where geometry was drawn.
//
// Receivers are Lambertian: L = albedo / pi * (E_direct * visibility + E_caustic),
// E_direct only when the scene has direct lighting, visibility from the shadow map
// only with the shadows effect. E_caustic, CAUSTIC_LOOKUP 0 (the paper's): looked
// up in the caustic map at the fragment's projection into the light's view (like a
// shadow-map lookup). The caustic map holds the irradiance of the receiver the light
// sees in that texel, so it is used only where the positions atlas shows this very
// fragment (same receiver, within three positions texels). CAUSTIC_LOOKUP 1: read
// in the receiver's own (u, v) map at the fragment's (u, v), which holds that
// receiver's caustic irradiance wherever the light lands on it (no visibility test).
// Receivers seen directly read it at the nearest texel, or bilinearly with
// FILTERED 1 (settings.lookup = "filtered").
//
// DEPTH_ONLY: the objects' depth pre-pass; the OBJECT variant then shades each
// pixel once (depth test <=) instead of every object fragment drawn before the
// nearest (1.8x the sphere's pixels, 1.2x the bunny's).
//
// OBJECT: a caustic object, seen along the event chain the photon tracer counts
// (scenes.event_chain), traced back from the eye (the paper's Fig. 1 uses double
// refraction "for the appearance of the bunny as well as for the caustics"):
//   conductor (L R D):          reflect the view ray, weight by the reflectance;
//   open dielectric (L T D):    refract once (water), Beer-Lambert to the receiver,
//                               radiance / ior^2 (radiance / n^2 is invariant along
//                               a ray; through a closed object the factors cancel);
//   closed dielectric (L T T D): refract in at the front point x; find the exit in
//     the back faces from the camera (camera_backfaces.glsl; Wyman 2005), starting
//     from Wyman's d_V = |B(x) - x| (the back face along the view ray); refract out
//     with the back face's normal. Total internal reflection there ends the chain
//     (black), or with ALL_PATHS reflects inside and looks for the next exit (at
//     most MAX_INTERNAL times).
// Fresnel (with the effect): each transmission is weighted by 1 - F; absorption
// (with the effect): exp(-K_a * path length inside); dispersion: one path per
// channel, each with its own IOR. The ray leaving the object meets the receivers
// where the preset's estimator finds the hit in the light's receiver positions
// atlas, as the caustic pass finds its hits (surface_estimate.glsl: the same
// estimators, iterations and reads; the safeguarded secant runs on the signed
// depth, see there). A ray for which it finds no receiver (an empty lookup; with
// verified hits also a residual above one positions texel) sees the empty sky:
// black. The receiver point T(P) the light sees through the estimate P is shaded as
// above: direct light with the shadow test, and the caustic map read bilinearly
// over the texels that show the same receiver.
#include "common.glsl"
#ifndef CAUSTIC_LOOKUP
#define CAUSTIC_LOOKUP 0
#endif
#ifndef FILTERED
#define FILTERED 0
#endif
#if defined VERTEX_SHADER
invariant gl_Position;      // the DEPTH_ONLY pre-pass and the shading pass agree exactly
#endif
#include "mesh_vertex.glsl"

uniform vec3 u_eye;                // m; u_vp (mesh_vertex.glsl) is the camera's world -> clip
uniform vec3 u_albedo;
uniform int u_receiver;
uniform int u_direct;              // scene has direct lighting
uniform int u_shadows;             // shadows effect
uniform int u_caustics;            // a caustic map is bound
uniform sampler2D u_shadow_map;    // RG32F: r light distance, g coverage
uniform int u_shadow_size;
uniform float u_shadow_bias;       // m
uniform sampler2D u_caustic_map;   // RGBA32F: rgb E (W/m^2), a kernel weight
uniform int u_caustic_size;
uniform sampler2D u_positions;     // receiver positions atlas (layout in common.glsl)
uniform int u_positions_size;
uniform sampler2D u_receiver_maps; // RGBA32F atlas: receiver i's (u, v) map, rgb E (W/m^2),
uniform ivec2 u_receiver_size;     // in the u_receiver_size (W, H) slot from column i * W
uniform sampler2D u_receiver_triangles; // with u_triangles_scale > 0, the triangles'
uniform int u_triangles_scale;     // part, in slots that many times finer per side
uniform sampler2D u_receiver_uv;   // RGBA32F (receivers, 4): row 0 and 1 the affine (u, v)
                                   // rows, 2 the (u, v) extent, 3 x: 1 if (u, v) is affine
uniform sampler2D u_uvs;           // the positions atlas's companion: xy (u, v)
// OBJECT variant
uniform sampler2D u_receiver_normals;  // its companion: xyz unit receiver normal
uniform sampler2D u_albedos;       // RGBA32F, (receivers, 1): rgb albedo of receiver i
uniform sampler2D u_back_positions;    // camera back faces: xyz (m), w object + 1
uniform sampler2D u_back_normals;      // xyz unit outward normal
uniform ivec2 u_viewport;          // camera image W, H (px)
uniform float u_pixel_width;       // width of one pixel at unit distance (tangent)
uniform int u_object;              // object index
// Compile-time: CAUSTIC_LOOKUP (0: the caustic map, 1: the receivers' (u, v) maps),
// FILTERED (1: bilinear reads within one surface, and of the caustic irradiance of
// receivers seen directly), and OBJECT's MATERIAL (0 none: black, 1 closed
// dielectric, 2 open dielectric, 3 conductor), DISPERSION (1: one path per channel),
// ALL_PATHS (1: TIR reflects, else it ends the chain), and the estimator's
// ESTIMATOR and SAFEGUARDED (surface_estimate.glsl).
// Each variant holds only its own path: on llvmpipe, uniform branches and loops
// over all of them (every call inlined, constant loops unrolled) made the object
// draw 5x slower for the material and dispersion, 1.5x for the estimator.
uniform vec3 u_ior;                // per channel
uniform vec3 u_absorption;         // K_a (1/m); zero without the absorption effect
uniform vec3 u_reflectance;
uniform int u_fresnel;             // 1: Fresnel transmittance at each interface
uniform int u_start;               // 0: d_1 = g(0), 1: d_1 = u_start_distance
uniform float u_start_distance;    // m
uniform int u_verify;              // 1: verified receiver hits
uniform float u_hit_tolerance;     // m; <= 0: one positions texel over the cosine

const int MAX_INTERNAL = 2;        // internal reflections followed (ALL_PATHS)
const int SURFACE_RECEIVERS = 0;   // the light's receiver positions atlas
const int SURFACE_BACK = 1;        // the camera's back faces of object u_object
const float PI = 3.14159265358979;

// Direct irradiance (W/m^2) at receiver point x, normal n, shadow-tested at its
// projection (face, ndc) into the light's map views (found: it has one).
vec3 direct_part(vec3 x, vec3 n, int face, vec2 ndc, bool found) {
    if (u_direct == 0) return vec3(0.0);
    float visible = 1.0;
    if (u_shadows == 1 && found) {
        vec4 s = texelFetch(u_shadow_map, map_texel(face, ndc, u_shadow_size), 0);
        if (s.g > 0.5 && s.r < light_distance(x) - u_shadow_bias) visible = 0.0;
    }
    return visible * direct_irradiance(x, n);
}

// The caustic map at `ndc` in view `face`, bilinear over the four nearest texels
// that show `receiver` (the receiver the positions atlas shows at each texel's
// centre), their weights renormalised; the nearest texel where none does.
vec3 caustic_filtered(int face, vec2 ndc, int receiver) {
    int size = u_caustic_size;
    vec2 q = clamp((ndc * 0.5 + 0.5) * float(size) - 0.5, vec2(0.0), vec2(float(size - 1)));
    ivec2 i0 = min(ivec2(floor(q)), ivec2(max(size - 2, 0)));
    vec2 f = q - vec2(i0);
    int base = max(u_map_slot[face], 0) * size;
    vec3 sum = vec3(0.0);
    float weight = 0.0;
    for (int j = 0; j < 2; ++j) {
        for (int i = 0; i < 2; ++i) {
            ivec2 c = min(i0 + ivec2(i, j), ivec2(size - 1));
            vec2 centre = (vec2(c) + 0.5) / float(size) * 2.0 - 1.0;
            vec4 tag = texelFetch(u_positions, map_texel(face, centre, u_positions_size), 0);
            if (int(tag.w + 0.5) - 1 != receiver) continue;
            float w = (i == 0 ? 1.0 - f.x : f.x) * (j == 0 ? 1.0 - f.y : f.y);
            sum += w * texelFetch(u_caustic_map, ivec2(base + c.x, c.y), 0).rgb;
            weight += w;
        }
    }
    if (weight > 0.0) return sum / weight;
    return texelFetch(u_caustic_map, map_texel(face, ndc, size), 0).rgb;
}

#if CAUSTIC_LOOKUP == 1
// Slot `slot` (size texels, from column slot * size.x) of atlas `map` at pixel
// coordinates pix (0 <= pix <= size): the nearest texel or, `filtered`, bilinear over
// the four around (clamped to the slot's edge texels).
vec3 slot_read(sampler2D map, ivec2 size, int slot, vec2 pix, bool filtered) {
    ivec2 base = ivec2(slot * size.x, 0);
    if (!filtered) return texelFetch(map, base + min(ivec2(pix), size - 1), 0).rgb;
    vec2 q = clamp(pix - 0.5, vec2(0.0), vec2(size - 1));
    ivec2 i0 = min(ivec2(floor(q)), max(size - 2, ivec2(0)));
    vec2 f = q - vec2(i0);
    vec3 a = mix(texelFetch(map, base + i0, 0).rgb,
                 texelFetch(map, base + i0 + ivec2(1, 0), 0).rgb, f.x);
    vec3 b = mix(texelFetch(map, base + i0 + ivec2(0, 1), 0).rgb,
                 texelFetch(map, base + i0 + ivec2(1, 1), 0).rgb, f.x);
    return mix(a, b, f.y);
}

// Receiver `receiver`'s (u, v) map at point x of it (projected into the light's
// views at (face, ndc); found: it has one), plus its finer triangles' part: each
// read by slot_read. The (u, v) is affine in x, or (a mesh) the one the positions
// atlas stores at x's texel, where that texel shows this receiver (else no caustic
// is read).
vec3 caustic_uv(vec3 x, int receiver, bool filtered, int face, vec2 ndc, bool found) {
    vec2 uv;
    if (texelFetch(u_receiver_uv, ivec2(receiver, 3), 0).x > 0.5) {
        uv = vec2(dot(texelFetch(u_receiver_uv, ivec2(receiver, 0), 0), vec4(x, 1.0)),
                  dot(texelFetch(u_receiver_uv, ivec2(receiver, 1), 0), vec4(x, 1.0)));
    } else {
        if (!found) return vec3(0.0);
        ivec2 t = map_texel(face, ndc, u_positions_size);
        if (int(texelFetch(u_positions, t, 0).w + 0.5) - 1 != receiver) return vec3(0.0);
        uv = texelFetch(u_uvs, t, 0).xy;
    }
    vec4 extent = texelFetch(u_receiver_uv, ivec2(receiver, 2), 0);   // umin umax vmin vmax
    vec2 at = (uv - extent.xz) / vec2(extent.y - extent.x, extent.w - extent.z);
    if (any(lessThan(at, vec2(0.0))) || any(greaterThan(at, vec2(1.0)))) return vec3(0.0);
    vec3 e = slot_read(u_receiver_maps, u_receiver_size, receiver,
                       at * vec2(u_receiver_size), filtered);
    if (u_triangles_scale > 0) {
        ivec2 fine = u_triangles_scale * u_receiver_size;
        e += slot_read(u_receiver_triangles, fine, receiver, at * vec2(fine), filtered);
    }
    return e;
}
#endif

// Irradiance (W/m^2) at point x (unit normal n) of receiver `receiver`: the direct
// light, shadow-tested, plus the caustic irradiance: from the receiver's (u, v) map
// (caustic_uv), or from the caustic map where the light's positions atlas shows x
// itself (the same receiver, within three positions texels), read at the nearest
// texel or, `filtered`, by caustic_filtered. One projection into the light's views
// serves the map lookups.
vec3 receiver_irradiance(vec3 x, vec3 n, int receiver, bool filtered) {
    int face;
    vec2 ndc;
    bool found = map_project(x, face, ndc);
    vec3 e = direct_part(x, n, face, ndc, found);
#if CAUSTIC_LOOKUP == 1
    if (u_caustics == 1) e += caustic_uv(x, receiver, filtered, face, ndc, found);
#else
    if (u_caustics == 1 && found) {
        vec4 p = texelFetch(u_positions, map_texel(face, ndc, u_positions_size), 0);
        float tol = 3.0 * sqrt(map_texel_area(x, n, ndc, u_positions_size));
        if (int(p.w + 0.5) - 1 == receiver && length(p.xyz - x) <= tol) {
            if (filtered) e += caustic_filtered(face, ndc, receiver);
            else e += texelFetch(u_caustic_map, map_texel(face, ndc, u_caustic_size), 0).rgb;
        }
    }
#endif
    return e;
}

// Radiance (W m^-2 sr^-1) of a receiver drawn directly (albedo `albedo`).
vec3 receiver_radiance(vec3 x, vec3 n, vec3 albedo, int receiver) {
    return albedo / PI * receiver_irradiance(x, n, receiver, FILTERED == 1);
}

#if defined FRAGMENT_SHADER && defined OBJECT
// Radiance (W m^-2 sr^-1) of receiver `receiver` at point y, normal n, seen
// through the object: as for receivers seen directly, the caustic map always read
// bilinearly.
vec3 hit_radiance(vec3 y, vec3 n, int receiver) {
    return texelFetch(u_albedos, ivec2(receiver, 0), 0).rgb / PI
        * receiver_irradiance(y, n, receiver, true);
}

// T(x): the receiver the light sees through x, position t (w: receiver + 1) and
// unit normal n, read as the caustic trace reads them (receiver_lookup, common.glsl);
// false where none is seen.
bool receiver_seen(vec3 x, out vec4 t, out vec3 n) {
    return receiver_lookup(u_positions, u_receiver_normals, u_positions_size, FILTERED == 1,
                           x, t, n);
}

// The verified hit's tolerance at p (normal n) without u_hit_tolerance: the
// caustic trace's, one positions-map texel over |cos| between the light ray and n
// (clamped at 0.1).
float hit_tolerance(vec3 p, vec3 n) {
    return map_texel_width(p, u_positions_size) / max(abs(dot(n, incident_dir(p))), 0.1);
}

// B(x): the back face of object u_object that the camera sees through x, position p
// (w: object + 1) and unit outward normal n; false where there is none.
bool back_at(vec3 x, out vec4 p, out vec3 n) {
    vec2 ndc;
    p = vec4(0.0);
    n = vec3(0.0);
    if (!project(u_vp, x, ndc)) return false;
    vec2 pix = (ndc * 0.5 + 0.5) * vec2(u_viewport);
    if (FILTERED == 1) {
        Bilinear b = bilinear_block(u_back_positions, ivec2(0), u_viewport, pix);
        p = bilinear_read(u_back_positions, b);
        n = bilinear_read(u_back_normals, b).xyz;
        if (dot(n, n) > 0.0) n = normalize(n);
    } else {
        ivec2 t = min(ivec2(floor(pix)), u_viewport - 1);
        p = texelFetch(u_back_positions, t, 0);
        n = texelFetch(u_back_normals, t, 0).xyz;
    }
    return abs(p.w - float(u_object + 1)) < 0.5;
}

bool surface_at(int surface, vec3 x, out vec4 t) {
    vec3 n;
    return surface == SURFACE_BACK ? back_at(x, t, n) : receiver_seen(x, t, n);
}

// One pixel of the back-face image, or one positions-atlas texel, at x (m).
float surface_texel(int surface, vec3 x) {
    return surface == SURFACE_BACK ? u_pixel_width * length(x - u_eye)
                                   : map_texel_width(x, u_positions_size);
}

float projection_distance(int surface, vec3 x) {
    return surface == SURFACE_BACK ? length(x - u_eye) : light_distance(x);
}

#include "surface_estimate.glsl"

// The preset's estimate of d along v + d r on `surface`, from d_1 = `start` (< 0:
// g(0)): the safeguarded secant as the bracketed secant on the signed depth, every
// other estimator as the caustic trace runs it (estimators.glsl). `d_seen`:
// the last estimate whose lookup saw the surface (-1: not tracked or none).
int estimate_ray(int surface, vec3 v, vec3 r, float start, out float d, out float d_seen) {
#if ESTIMATOR == 2 && SAFEGUARDED == 1
    d_seen = -1.0;
    return bracket_on(surface, v, r, start, d);
#else
    return estimate_along(surface, v, r, start, ESTIMATOR, SAFEGUARDED == 1, 0, d, d_seen);
#endif
}

// Where the ray from x (inside the object) along unit r leaves it: exit point e,
// the exit surface's unit outward normal bn, and the chord length len = |e - x| (m).
// Wyman 2005 takes d_V, the back face along the view ray, as the distance (blended
// with a precomputed d_N); here d_V is the start d_1 = g(0) = |B(x) - x| (x projects
// to its own pixel) of the preset's estimator along r on the back faces, as the
// caustic trace refines its exit (caustic_trace.glsl, find_exit): at the root the
// estimate lies on the back surface. `start` > 0 gives d_1 instead (after an
// internal reflection, where x itself lies on the back surface). A front pixel
// whose own back face is missing (the two rasterise differently at the silhouette)
// steps 2, 4, 8, 16 pixels inside along r to find one. If the final estimate's
// lookup sees no back face, the normal is the last one seen (the estimate is kept,
// as in find_exit).
bool find_exit(vec3 x, vec3 r, float start, out vec3 e, out vec3 bn, out float len) {
    vec4 p;
    e = x;
    len = 0.0;
    if (start <= 0.0 && !back_at(x, p, bn)) {
        float pixel = u_pixel_width * length(x - u_eye);
        bool ok = false;
        for (int k = 1; k <= 4 && !ok; ++k) ok = back_at(x + pixel * exp2(float(k)) * r, p, bn);
        if (!ok) return false;
        start = length(p.xyz - x);
    }
    vec3 fallback = bn;
    float d, d_seen;
    estimate_ray(SURFACE_BACK, x, r, start > 0.0 ? start : -1.0, d, d_seen);
    if (!(d > 0.0 && d < 1e30)) return false;
    if (!back_at(x + d * r, p, bn)) {
        if (d_seen < 0.0 || !back_at(x + d_seen * r, p, bn)) bn = fallback;
    }
    e = x + d * r;
    len = d;
    return dot(bn, bn) > 0.0;
}

// Radiance arriving at v from along unit r: the receiver hit the estimator finds
// in the light's positions atlas, shaded there; `dist` the distance to it (m).
vec3 receiver_along(vec3 v, vec3 r, out float dist) {
    dist = 0.0;
    float d, d_seen;
    int status = estimate_ray(SURFACE_RECEIVERS, v, r, u_start == 1 ? u_start_distance : -1.0,
                              d, d_seen);
    if (status != STATUS_HIT || !(d > 0.0 && d < 1e30)) return vec3(0.0);
    vec3 p = v + d * r;
    vec4 t;
    vec3 n;
    if (!receiver_seen(p, t, n)) return vec3(0.0);
    if (u_verify == 1) {              // the caustic trace's verified hit
        float tol = u_hit_tolerance > 0.0 ? u_hit_tolerance : hit_tolerance(p, n);
        if (length(t.xyz - p) > tol) return vec3(0.0);
    }
    dist = length(t.xyz - v);
    return hit_radiance(t.xyz, n, int(t.w + 0.5) - 1);
}

// Radiance seen at front point x (unit normal n facing the eye) along unit view
// direction dv, for a material of index `ior`.
vec3 object_radiance(vec3 x, vec3 n, vec3 dv, float ior) {
    float dist;
#if MATERIAL == 3
    return u_reflectance * receiver_along(x, reflect(dv, n), dist);
#else
    vec3 r = refract(dv, n, 1.0 / ior);
    vec3 weight = vec3(1.0);
    if (u_fresnel == 1) weight *= fresnel_transmittance(-dot(dv, n), 1.0, ior);
#if MATERIAL == 2                     // water: one refraction, absorbed down to the floor
    // Radiance over n^2 is invariant along a ray (Veach 1997, 5.2): the floor's
    // radiance in water reaches the eye in air divided by ior^2. (Through a closed
    // dielectric the factors of the way in and out cancel.)
    vec3 seen = receiver_along(x, r, dist);
    return weight * exp(-u_absorption * dist) * seen / (ior * ior);
#else
    float inside = 0.0, start = 0.0;
    vec3 v = x;
    for (int bounce = 0; bounce <= (ALL_PATHS == 1 ? MAX_INTERNAL : 0); ++bounce) {
        vec3 e, bn;
        float len;
        if (!find_exit(v, r, start, e, bn, len)) return vec3(0.0);
        inside += len;
        vec3 m = dot(r, bn) > 0.0 ? -bn : bn;        // exit normal facing the inside ray
        vec3 out_dir = refract(r, m, ior);
        if (dot(out_dir, out_dir) > 0.0) {
            if (u_fresnel == 1) weight *= fresnel_transmittance(-dot(r, m), ior, 1.0);
            weight *= exp(-u_absorption * inside);   // Beer-Lambert (paper Eq. 7)
            return weight * receiver_along(e, out_dir, dist);
        }
        // L T T D only (chain mode): TIR counts nothing. All paths: reflect inside;
        // the next chord starts as long as this one (equal chords in a sphere).
        r = reflect(r, m);
        v = e;
        start = len;
    }
    return vec3(0.0);
#endif
#endif
}
#endif

#if defined FRAGMENT_SHADER
out vec4 out_radiance;
void main() {
    vec3 n = normalize(v_normal);
#if defined DEPTH_ONLY
    out_radiance = vec4(0.0);
#elif defined OBJECT
    vec3 dv = normalize(v_position - u_eye);
    if (dot(n, dv) > 0.0) n = -n;                    // face the eye (two-sided surfaces)
    vec3 color = vec3(0.0);
#if MATERIAL == 0
#elif DISPERSION == 1
    for (int c = 0; c < 3; ++c) color[c] = object_radiance(v_position, n, dv, u_ior[c])[c];
#else
    color = object_radiance(v_position, n, dv, u_ior.x);
#endif
    out_radiance = vec4(color, 1.0);
#else
    out_radiance = vec4(receiver_radiance(v_position, n, u_albedo, u_receiver), 1.0);
#endif
}
#endif
