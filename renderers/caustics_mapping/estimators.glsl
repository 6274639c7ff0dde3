// The intersection estimators (paper Section 3.3 and its appendix; distance
// impostors), one copy for every pass that runs them: the caustic trace
// (caustic_trace.glsl) on the light's receiver positions atlas, and the camera pass
// (surface_estimate.glsl) on that atlas and on the camera's back faces. The NumPy
// mirror in estimators.py does the same arithmetic. Included after common.glsl; the
// includer defines, before including this file,
//   bool surface_at(int surface, vec3 x, out vec4 t)
//       T(x): the point (t.xyz, m) of surface `surface` seen through x's projection
//       into that surface's image; false where the image shows none there;
//   void estimate_record(int record, int k, float d)
//       called with the estimate d (m) after k = 0, 1, ..., u_iterations updates
//       (the caustic trace's per-vertex history; a no-op elsewhere).
//
// Along the ray P(d) = v + d r (unit r), with g(d) = |T(P(d)) - v| and
// h(d) = g(d) - d (the hit solves h = 0):
//   modified (paper):     d <- g(d)
//   newton (appendix):    f(d) = |T(P(d)) - P(d)|, d <- d - f(d) eps / (f(d+eps) - f(d))
//   secant (distance impostors): d <- d - h(d) (d - d_prev) / (h(d) - h(d_prev))
// starting from d_0 = 0, d_1 = g(0) (the surface seen along the projection ray through
// v), or from a given d_1 (secant's first update is then the modified one, having no
// previous point).
// Safeguarded: a bracket [lo, hi] with h(lo) >= 0 >= h(hi) is kept from every
// lookup. An estimate whose lookup sees no surface has overshot the surface's edge:
// it becomes an upper end, and the next estimate is halfway back to the last one
// that saw the surface. An update that is non-finite, leaves the bracket (or, with no
// upper end yet, goes past twice the modified update's distance max(g, lo): a trust
// region), or oscillates (reverses direction without at least halving the step, from
// the last two estimates) is replaced by the false-position point of the bracket
// where both ends' residuals are known (inside the bracket, and next to the end with
// the smaller |h|) and it does not itself oscillate, else by the bracket's bisection
// (or by the modified step while no upper end is known). Bisection threw good estimates away: h is piecewise smooth (bilinear
// reads; kinks at texel borders), a secant across a kink reverses, and halving a
// bracket [0, hi] whose hi is within a hundredth of a texel of the root undid it.
// Unsafeguarded, a non-finite update ends the iterations as STATUS_DIVERGED; a lookup
// that sees no surface ends them as STATUS_LOST. The estimate is then kept, and
// recorded again for each remaining update.
// Converged: an estimate whose residual |h(d)| is at most
// ESTIMATE_TOLERANCE(surface, P(d)) (m; the includer may define it before including
// this file, default 0: only h = 0)
// ends the iterations and is kept. Once |h| is at the lookups' resolution (float32
// rounding and the bilinear reads' error), h's sign and the secant's slope are noise:
// on metal_ring's reflected rays d_1 = g(0) is already the root (a vertical mirror
// keeps the light ray's slope), the next secant step through two points with
// |h| ~ 1e-5 m lands a hair past the bracket's end, and the safeguard's bisection
// then threw the root away for half the distance (33 % of the reflected flux
// unconverged after 5 updates).

#ifndef ESTIMATE_TOLERANCE
#define ESTIMATE_TOLERANCE(surface, x) 0.0
#endif

uniform int u_iterations;       // updates after d_1
uniform float u_eps;            // Newton's finite-difference step (m)

// g(d) and T(P(d)) (m); false where no surface is seen at P(d).
bool surface_g(int surface, vec3 v, vec3 r, float d, out float g, out vec3 t) {
    vec4 q;
    bool ok = surface_at(surface, v + d * r, q);
    t = q.xyz;
    g = length(q.xyz - v);
    return ok;
}

// Estimate d (m) on `surface` along v + d r with `estimator` (0 modified, 1 newton,
// 2 secant), from d_1 = `start` (start < 0: d_1 = g(0)). Returns STATUS_HIT (the
// iterations ran; the residual is not tested), STATUS_LOST (a lookup saw no surface,
// unsafeguarded, or d_1 = g(0) had none: d = 0) or STATUS_DIVERGED. `d_seen` is the
// last estimate whose lookup saw the surface (-1: none). A compile-time `estimator`
// and `safeguarded` leave only their own arithmetic once the call is inlined.
int estimate_along(int surface, vec3 v, vec3 r, float start, int estimator, bool safeguarded,
                   int record, out float d_out, out float d_seen) {
    vec3 t;
    d_out = 0.0;
    d_seen = -1.0;
    float d, d_prev = 0.0, h_prev = 0.0;
    bool have_prev = false;          // secant needs a previous point
    if (start >= 0.0) {
        d = start;
    } else {
        float g0;
        if (!surface_g(surface, v, r, 0.0, g0, t)) {
            for (int k = 0; k <= u_iterations; ++k) estimate_record(record, k, 0.0);
            return STATUS_LOST;
        }
        d = g0;
        h_prev = g0;                 // h(0) = g(0) - 0
        have_prev = true;
        d_seen = 0.0;
    }
    float lo = 0.0, hi = -1.0;       // bracket of the root of h; hi < 0: no upper end yet
    float h_lo = h_prev, h_hi = 0.0; // h at the bracket's ends, where known
    bool lo_known = have_prev, hi_known = false;
    int status = STATUS_HIT;
    estimate_record(record, 0, d);
    int k = 1;
    for (; k <= u_iterations; ++k) {
        float g;
        if (!surface_g(surface, v, r, d, g, t)) {
            // Safeguarded: step back halfway to the last estimate that saw the
            // surface. The missed point becomes the previous one, so that a jump
            // forward again is caught as oscillation (secant restarts: h there is
            // unknown).
            if (safeguarded && d_seen >= 0.0) {
                if (hi < 0.0 || d < hi) { hi = d; hi_known = false; }
                d_prev = d;
                have_prev = false;
                d = 0.5 * (d_seen + d);
                estimate_record(record, k, d);
                continue;
            }
            status = STATUS_LOST;
            break;
        }
        d_seen = d;
        float h = g - d;
        if (abs(h) <= ESTIMATE_TOLERANCE(surface, v + d * r)) break;   // converged: kept
        if (h >= 0.0) {
            if (d >= lo) { lo = d; h_lo = h; lo_known = true; }
        } else if (hi < 0.0 || d <= hi) {
            hi = d; h_hi = h; hi_known = true;
        }
        float prop = d;
        bool finite = true;
        if (h == 0.0) {
            prop = d;                               // at the root
        } else if (estimator == 0) {
            prop = g;                               // modified: d <- g(d)
        } else if (estimator == 2) {
            float den = h - h_prev;                 // secant on h
            if (!have_prev) prop = g;               // fixed start: no previous point
            else if (den != 0.0) prop = d - h * (d - d_prev) / den;
            else finite = false;
        } else {
            float f = length(t - (v + d * r));      // Newton on f, forward difference
            float g2;
            vec3 t2;
            if (!surface_g(surface, v, r, d + u_eps, g2, t2)) {
                status = STATUS_LOST;
                break;
            }
            float fe = length(t2 - (v + (d + u_eps) * r));
            float den = fe - f;
            if (f == 0.0) prop = d;
            else if (den != 0.0) prop = d - f * u_eps / den;
            else finite = false;
        }
        if (!(abs(prop) < 1e30)) finite = false;
        if (safeguarded) {
            bool osc = k >= 2 && (prop - d) * (d - d_prev) < 0.0
                && abs(prop - d) >= 0.5 * abs(d - d_prev);
            bool outside = prop < lo || (hi >= 0.0 ? prop > hi : prop > 2.0 * max(g, lo));
            if (!finite || osc || outside) {
                prop = hi < 0.0 ? g : 0.5 * (lo + hi);
                if (hi >= 0.0 && lo_known && hi_known && h_lo > h_hi) {
                    float fp = lo + h_lo * (hi - lo) / (h_lo - h_hi);   // false position
                    bool fp_osc = k >= 2 && (fp - d) * (d - d_prev) < 0.0
                        && abs(fp - d) >= 0.5 * abs(d - d_prev);
                    if (!fp_osc) prop = fp;
                }
            }
        } else if (!finite) {
            status = STATUS_DIVERGED;
            break;
        }
        d_prev = d;
        h_prev = h;
        have_prev = true;
        d = prop;
        estimate_record(record, k, d);
    }
    for (; k <= u_iterations; ++k) estimate_record(record, k, d);   // ended early: kept
    d_out = d;
    return status;
}
