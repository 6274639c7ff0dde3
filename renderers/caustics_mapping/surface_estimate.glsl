// The intersection estimators of the caustic trace (estimators.glsl: the same
// arithmetic, without its per-iteration history) on any image-space surface, and
// the camera pass's bracketed secant on the depth. The includer defines, before
// including this file,
//   bool surface_at(int surface, vec3 x, out vec4 t)
//   float projection_distance(int surface, vec3 x)
//   float surface_texel(int surface, vec3 x)
// : the point T(x) of surface `surface` seen through x's projection into that
// surface's image (t.xyz, m), false where the image shows none there; and the
// distance (m) of x from that image's centre of projection along its projection
// ray (the light's distance, or the depth along a directional light; the eye's
// distance); and the width (m) at x of one texel of that surface's image. As in the
// caustic trace, the estimators stop at an estimate within u_converged of those
// texels of the surface (0: only on it). It defines ESTIMATOR (0 modified, 1
// newton, 2 secant) and SAFEGUARDED (0 or 1) at compile time (as uniforms, on
// llvmpipe, every variant's code ran masked: 1.5x the time).

void estimate_record(int record, int k, float d) {}   // no history here

uniform float u_converged;
#define ESTIMATE_TOLERANCE(surface, x) (u_converged * surface_texel(surface, x))

#include "estimators.glsl"

// ------------------------------------------------ bracketed secant on the depth
// The camera pass's safeguarded secant. Camera rays run at any angle to the
// projection rays of the image they are traced in (a ring reflects the floor back
// towards a low light), and there h(d) (estimators.glsl) can touch zero without crossing it,
// or cross it several times: on metal_ring, 78 % of the ring's pixels whose exact
// reflection meets a lit floor failed the verified hit after 5 safeguarded secant
// steps on h. The signed depth
//     s(d) = D(P(d)) - D(T(P(d))),   D = projection_distance,
// is negative while P is in front of the surface seen through it and positive once
// P is behind it, so it changes sign exactly where the ray crosses the surface
// (linearly in d for a plane).
// A lookup that sees no surface (the point's image falls off the surface's, e.g.
// past a receiver's edge) tells nothing of the side: it is taken to lie on the side
// whose sign is still unknown (in front before any point in front was seen: the ray
// starts in front of the surface; behind once one was), and the next step bisects.
// 1. Bracket: from d = 0 (s < 0, or no surface seen there) probe d_1 (`start`; g(0);
//    u_ray_scale where v sees no surface), doubling it while the probe is in front,
//    at most BRACKET_PROBES lookups.
// 2. Refine, u_iterations lookups: the secant point of the bracket with the
//    Illinois rule (an end kept twice in a row has its s halved: regula falsi
//    without its one-sided stall); while one end's s is unknown, the secant through
//    the last two points in front if it falls inside, else bisection. A point whose
//    |s| is within ESTIMATE_TOLERANCE (a hundredth of a texel with the safeguard)
//    lies on the surface to the lookups' resolution: it is the estimate, and the
//    iterations end (strong on bunny: camera excess relMSE 3.975e-3 -> 3.980e-3,
//    its 95 % interval +-7e-5; the object's shading 56 -> 51 ms on llvmpipe).
// The estimate is the final bracket's secant point, or its upper end where the
// lower end's s is unknown; STATUS_LOST where no point behind was found.

uniform float u_ray_scale;      // m: first probe where v sees no surface

const int BRACKET_PROBES = 8;   // d_1 up to 128 d_1

bool surface_s(int surface, vec3 v, vec3 r, float d, out float s) {
    vec4 t;
    vec3 p = v + d * r;
    bool ok = surface_at(surface, p, t);
    s = projection_distance(surface, p) - projection_distance(surface, t.xyz);
    return ok;
}

int bracket_on(int surface, vec3 v, vec3 r, float start, out float d_out) {
    d_out = 0.0;
    float a = 0.0, sa = 0.0, b = start, sb = 0.0;
    vec4 t0;                        // the surface seen through v itself (d = 0)
    bool a_known = surface_at(surface, v, t0);          // s(a) known (else assumed < 0)
    sa = projection_distance(surface, v) - projection_distance(surface, t0.xyz);
    if (a_known && !(sa < 0.0)) {   // on the surface already (after a reflection there)
        a = 1e-3 * max(start, 0.0);
        a_known = a > 0.0 && surface_s(surface, v, r, a, sa);
        if (a_known && !(sa < 0.0)) return STATUS_LOST;
    }
    if (!(b > a)) {                 // d_1 = g(0) = |T(v) - v|, from the lookup above
        b = a_known && a == 0.0 ? length(t0.xyz - v) : u_ray_scale;
        b = max(b, 2.0 * a);
    }
    float a_prev = -1.0, sa_prev = 0.0;     // the known point in front before a
    bool bracketed = false, b_known = false;
    for (int k = 0; k < BRACKET_PROBES && !bracketed; ++k) {
        float sc;
        bool ok = surface_s(surface, v, r, b, sc);
        if (ok && sc >= 0.0) {
            sb = sc;
            bracketed = b_known = true;
        } else if (!ok && a_known) {
            bracketed = true;                           // past the edge: behind
        } else {                                        // in front: go on
            if (ok && a_known) { a_prev = a; sa_prev = sa; }
            a = b;
            sa = sc;
            a_known = ok;
            b *= 2.0;
        }
    }
    if (!bracketed) return STATUS_LOST;
    int side = 0;                   // the end that moved last: -1 a, +1 b
    for (int k = 0; k < u_iterations; ++k) {
        float c = 0.5 * (a + b);
        if (a_known && b_known) {
            c = b - sb * (b - a) / (sb - sa);
        } else if (a_known && a_prev >= 0.0 && sa != sa_prev) {
            float e = a - sa * (a - a_prev) / (sa - sa_prev);
            if (e > a && e < b) c = e;
        }
        float sc;
        bool ok = surface_s(surface, v, r, c, sc);
        if (ok && abs(sc) <= ESTIMATE_TOLERANCE(surface, v + c * r)) {
            d_out = c;
            return STATUS_HIT;
        }
        if (ok && sc >= 0.0) {
            b = c;
            sb = sc;
            if (side == 1 && a_known && b_known) sa *= 0.5;     // Illinois
            b_known = true;
            side = 1;
        } else if (ok || !a_known) {
            if (ok && a_known) { a_prev = a; sa_prev = sa; }
            a = c;
            sa = sc;
            if (side == -1 && a_known && b_known && ok) sb *= 0.5;   // Illinois
            a_known = ok;
            side = -1;
        } else {
            b = c;                                      // unknown, with a known: behind
            b_known = false;
            side = 1;
        }
    }
    if (!b_known) return STATUS_LOST;
    d_out = a_known ? b - sb * (b - a) / (sb - sa) : b;
    return STATUS_HIT;
}
