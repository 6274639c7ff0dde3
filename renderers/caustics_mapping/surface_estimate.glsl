// The intersection estimators of the caustic trace (caustic_trace.glsl, estimate(),
// the same arithmetic without its per-iteration history) on any image-space
// surface. The includer defines, before including this file,
//   bool surface_at(int surface, vec3 x, out vec4 t)
//   float projection_distance(int surface, vec3 x)
// : the point T(x) of surface `surface` seen through x's projection into that
// surface's image (t.xyz, m), false where the image shows none there; and the
// distance (m) of x from that image's centre of projection along its projection
// ray (the light's distance, or the depth along a directional light; the eye's
// distance). It defines ESTIMATOR (0 modified, 1 newton, 2 secant) and SAFEGUARDED
// (0 or 1) at compile time (as uniforms, on llvmpipe, every variant's code ran
// masked: 1.5x the time).
//
// With P(d) = v + d r, g(d) = |T(P(d)) - v|, h(d) = g(d) - d (the hit solves h = 0):
//   modified (paper):     d <- g(d)
//   newton (appendix):    f(d) = |T(P(d)) - P(d)|, d <- d - f(d) eps / (f(d+eps) - f(d))
//   secant (distance impostors): d <- d - h(d) (d - d_prev) / (h(d) - h(d_prev))
// from d_0 = 0, d_1 = g(0) (the surface seen through v itself), or from a given
// d_1 (secant's first update is then the modified one, having no previous point).
// Safeguarded: a bracket [lo, hi] with h(lo) >= 0 >= h(hi) is kept from every
// lookup; an estimate whose lookup sees no surface becomes an upper end and the
// next estimate is halfway back to the last one that saw the surface; an update
// that is non-finite, leaves the bracket (or, with no upper end yet, goes past twice
// the modified update), or oscillates (reverses without at least halving the step)
// is replaced by bisection of the bracket (or the modified step).

uniform int u_iterations;       // updates after d_1
uniform float u_eps;            // Newton's finite-difference step (m)

const int ESTIMATE_HIT = 1;     // the iterations ran (no test of the residual)
const int ESTIMATE_LOST = 2;    // a lookup saw no surface (unsafeguarded), or d_1 had none
const int ESTIMATE_DIVERGED = 4;

bool surface_g(int surface, vec3 v, vec3 r, float d, out float g, out vec3 t) {
    vec4 q;
    bool ok = surface_at(surface, v + d * r, q);
    t = q.xyz;
    g = length(q.xyz - v);
    return ok;
}

// Estimate d on `surface` along v + d r, starting from d_1 = `start` (start < 0:
// g(0)). `d_seen` is the last estimate whose lookup saw the surface (-1: none).
int estimate_on(int surface, vec3 v, vec3 r, float start, out float d_out,
                out float d_seen) {
    vec3 t;
    d_out = 0.0;
    d_seen = -1.0;
    float d, d_prev = 0.0, h_prev = 0.0;
    bool have_prev = false;          // secant needs a previous point
    if (start >= 0.0) {
        d = start;
    } else {
        float g0;
        if (!surface_g(surface, v, r, 0.0, g0, t)) return ESTIMATE_LOST;
        d = g0;
        h_prev = g0;                 // h(0) = g(0) - 0
        have_prev = true;
        d_seen = 0.0;
    }
    float lo = 0.0, hi = -1.0;       // bracket of the root of h; hi < 0: no upper end
    int status = ESTIMATE_HIT;
    for (int k = 1; k <= u_iterations; ++k) {
        float g;
        if (!surface_g(surface, v, r, d, g, t)) {
            if (SAFEGUARDED == 1 && d_seen >= 0.0) {   // overshot the surface's edge
                hi = hi < 0.0 ? d : min(hi, d);
                d_prev = d;
                have_prev = false;
                d = 0.5 * (d_seen + d);
                continue;
            }
            status = ESTIMATE_LOST;
            break;
        }
        d_seen = d;
        float h = g - d;
        if (h >= 0.0) lo = max(lo, d); else hi = hi < 0.0 ? d : min(hi, d);
        float prop = d;
        bool finite = true;
        if (h == 0.0) {
            prop = d;                                   // at the root
        } else if (ESTIMATOR == 0) {
            prop = g;                                   // modified: d <- g(d)
        } else if (ESTIMATOR == 2) {
            float den = h - h_prev;                     // secant on h
            if (!have_prev) prop = g;
            else if (den != 0.0) prop = d - h * (d - d_prev) / den;
            else finite = false;
        } else {
            float f = length(t - (v + d * r));          // Newton on f, forward difference
            float g2;
            vec3 t2;
            if (!surface_g(surface, v, r, d + u_eps, g2, t2)) { status = ESTIMATE_LOST; break; }
            float den = length(t2 - (v + (d + u_eps) * r)) - f;
            if (f == 0.0) prop = d;
            else if (den != 0.0) prop = d - f * u_eps / den;
            else finite = false;
        }
        if (!(abs(prop) < 1e30)) finite = false;
        if (SAFEGUARDED == 1) {
            bool osc = k >= 2 && (prop - d) * (d - d_prev) < 0.0
                && abs(prop - d) >= 0.5 * abs(d - d_prev);
            bool outside = prop < lo || (hi >= 0.0 ? prop > hi : prop > 2.0 * max(g, lo));
            if (!finite || osc || outside) prop = hi >= 0.0 ? 0.5 * (lo + hi) : g;
        } else if (!finite) {
            status = ESTIMATE_DIVERGED;
            break;
        }
        d_prev = d;
        h_prev = h;
        have_prev = true;
        d = prop;
    }
    d_out = d;
    return status;
}

// ------------------------------------------------ bracketed secant on the depth
// The camera pass's safeguarded secant. Camera rays run at any angle to the
// projection rays of the image they are traced in (a ring reflects the floor back
// towards a low light), and there h(d) above can touch zero without crossing it,
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
//    the last two points in front if it falls inside, else bisection.
// The estimate is the final bracket's secant point, or its upper end where the
// lower end's s is unknown; ESTIMATE_LOST where no point behind was found.

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
    bool a_known = surface_s(surface, v, r, 0.0, sa);   // s(a) known (else assumed < 0)
    if (a_known && !(sa < 0.0)) {   // on the surface already (after a reflection there)
        a = 1e-3 * max(start, 0.0);
        a_known = a > 0.0 && surface_s(surface, v, r, a, sa);
        if (a_known && !(sa < 0.0)) return ESTIMATE_LOST;
    }
    if (!(b > a)) {                 // d_1 = g(0): the surface seen through v itself
        vec4 t;
        b = a_known && a == 0.0 && surface_at(surface, v, t) ? length(t.xyz - v) : u_ray_scale;
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
    if (!bracketed) return ESTIMATE_LOST;
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
    if (!b_known) return ESTIMATE_LOST;
    d_out = a_known ? b - sb * (b - a) / (sb - sa) : b;
    return ESTIMATE_HIT;
}
