"""Convergence of the intersection estimators, measured against exact ray casts.

Input per grid vertex: the history of estimated hit distances d_0 .. d_k of one
render with k iterations (d_0 is the start estimate g(0)), whether the lookup lost
the receiver, and the exact distance d* along the same ray (v, r) from
``harness.raycast``. Errors are |d_k − d*| in metres and in caustic-map texels (the
metres divided by the footprint of one texel at the exact hit point).

Outcome of each vertex whose exact ray hits a receiver, with tolerance τ (default one
texel; steps Δ_j = d_j − d_{j−1} are measured in texels too):

* ``lost``        the estimator's lookup found no receiver (the splat is dropped);
* ``converged``   |d_k − d*| ≤ τ: the splat lands in the right texel;
* ``diverged``    d_k is not finite, or negative, or more than 10× the exact
  distance: the iteration ran away;
* ``oscillating`` the last two steps change sign and the last is at least 3/4 as
  long as the one before, and longer than τ: jumping between two estimates (the
  plain Newton-Raphson failure the paper describes). Bisection, which halves its
  step, is not oscillation;
* ``stalled``     |Δ_k| ≤ τ but |d_k − d*| > τ: stationary at a wrong fixed point of
  g, typically a receiver point the light sees that is not the ray's first hit
  (depth discontinuities, corrugated receivers);
* the rest are still converging (``converging``).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = ["LOOKUPS", "OUTCOMES", "IterationStats", "iteration_stats", "lookups_per_vertex",
           "texel_footprint"]

#: Positions-texture lookups: for the starting estimate g(0), and per iteration.
LOOKUPS = {"modified": (1, 1), "newton": (1, 2), "secant": (1, 1)}
OUTCOMES = ("converged", "diverged", "oscillating", "stalled", "converging", "lost")


def lookups_per_vertex(estimator: str, iterations: int, *, safeguarded: bool = False) -> int:
    """Texture lookups one vertex costs: start + per-iteration × iterations.

    The safeguarded forms reuse the values already fetched to detect oscillation and
    bisect with one lookup per step, so their count is the same upper bound.
    """
    start, per_iteration = LOOKUPS[estimator]
    return start + per_iteration * iterations


@dataclass(frozen=True)
class IterationStats:
    """Errors after ``iteration`` iterations and the fraction of each outcome
    (fractions of the vertices whose exact ray hits a receiver)."""

    iteration: int
    mean_error_m: float
    p95_error_m: float
    max_error_m: float
    mean_error_texels: float
    p95_error_texels: float
    max_error_texels: float
    converged: float
    diverged: float
    oscillating: float
    stalled: float
    converging: float
    lost: float


def _stats(values: np.ndarray) -> tuple[float, float, float]:
    if values.size == 0:
        return (float("nan"),) * 3
    return float(values.mean()), float(np.percentile(values, 95)), float(values.max())


def classify(history, lost, exact, texel_size, *, tolerance_texels: float = 1.0) -> np.ndarray:
    """Outcome name of each vertex (object array); ``""`` where the exact ray misses."""
    history = np.asarray(history, np.float64)
    lost = np.asarray(lost, bool)
    exact = np.asarray(exact, np.float64)
    texel = np.broadcast_to(np.asarray(texel_size, np.float64), exact.shape)
    final = history[:, -1]
    with np.errstate(invalid="ignore", over="ignore"):
        error = np.abs(final - exact) / texel
        steps = np.diff(history, axis=1) / texel[:, None]
    outcome = np.full(len(exact), "converging", dtype=object)
    last = steps[:, -1] if steps.shape[1] else np.zeros(len(exact))
    if steps.shape[1] >= 2:
        before = steps[:, -2]
        oscillating = ((np.sign(last) * np.sign(before) < 0)
                       & (np.abs(last) >= 0.75 * np.abs(before))
                       & (np.abs(last) > tolerance_texels))
        outcome[oscillating] = "oscillating"
    outcome[(np.abs(last) <= tolerance_texels) & (error > tolerance_texels)] = "stalled"
    outcome[error <= tolerance_texels] = "converged"
    runaway = ~np.isfinite(final) | (final < 0) | (final > 10 * exact)
    outcome[runaway] = "diverged"
    outcome[lost] = "lost"
    outcome[~np.isfinite(exact)] = ""
    return outcome


def iteration_stats(history, lost, exact, texel_size, *, iteration: int | None = None,
                    tolerance_texels: float = 1.0) -> IterationStats:
    """Statistics of one render's final estimates.

    Parameters
    ----------
    history : array (N, k+1)
        Estimated distance (m) after 0..k iterations, per vertex.
    lost : array (N,), bool
        The estimator's lookup found no receiver.
    exact : array (N,)
        Exact distance (m), ``inf`` where the ray misses every receiver (those
        vertices are excluded: there is nothing to converge to).
    texel_size : float or array (N,)
        Footprint of one caustic-map texel at the exact hit, metres.
    """
    history = np.asarray(history, np.float64)
    exact = np.asarray(exact, np.float64)
    if history.ndim != 2 or history.shape[0] != exact.size or np.shape(lost) != exact.shape:
        raise ValueError("history must be (N, k+1) and lost (N,) with N = len(exact)")
    texel = np.broadcast_to(np.asarray(texel_size, np.float64), exact.shape)
    outcome = classify(history, lost, exact, texel, tolerance_texels=tolerance_texels)
    valid = outcome != ""
    count = max(int(valid.sum()), 1)
    with np.errstate(invalid="ignore"):
        error = np.abs(history[:, -1] - exact)
    ok = valid & (outcome != "lost") & np.isfinite(error)
    fractions = {name: float((outcome == name).sum() / count) for name in OUTCOMES}
    k = history.shape[1] - 1 if iteration is None else iteration
    return IterationStats(k, *_stats(error[ok]), *_stats((error / texel)[ok]), **fractions)


def texel_footprint(setups, light: np.ndarray, points: np.ndarray, *, size: int) -> np.ndarray:
    """Width (m) of one caustic-map texel at each point, seen from the light sample
    that traced it (``light`` indexes ``setups``, the renderer's light setups): 2 t d / M
    for a perspective view of half-angle tangent t at distance d, 2 h / M for an
    orthographic view of half-width h; M = ``size`` texels."""
    out = np.empty(len(points))
    for index, setup in enumerate(setups):
        mine = light == index
        view = setup.map_views[0]
        if view.perspective:
            distance = np.linalg.norm(points[mine] - setup.position, axis=1)
            out[mine] = 2 * view.half_size * distance / size
        else:
            out[mine] = 2 * view.half_size / size
    return out
