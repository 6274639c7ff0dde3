"""Convergence of the intersection estimators, measured against exact ray casts.

Inputs are per grid vertex: the estimated hit distance after each iteration
(``estimates[k]`` after k iterations, k = 0 the starting estimate d = g(0)), whether
the lookup lost the receiver, and the exact distance along the same ray (v, r) from
``harness.raycast``. Errors are |d_k − d*| in metres and in caustic-map texels (the
metres divided by the footprint of one texel at the exact hit point).

Outcome per vertex and iteration (vertices whose exact ray hits a receiver):

* ``lost``      the estimator's lookup found no receiver (the splat is dropped);
* ``converged`` error ≤ ``tolerance_texels`` (default 1 texel: the splat lands in
  the right texel);
* ``diverged``  non-finite, or error above ``tolerance_texels`` and larger than the
  starting estimate's (iterating moved the estimate away from the answer);
* the rest are still converging.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = ["LOOKUPS", "IterationStats", "iteration_stats", "lookups_per_vertex"]

#: Positions-texture lookups: for the starting estimate g(0), and per iteration.
LOOKUPS = {"modified": (1, 1), "newton": (1, 2), "secant": (1, 1)}


def lookups_per_vertex(estimator: str, iterations: int, *, safeguarded: bool = False) -> int:
    """Texture lookups one vertex costs: start + per-iteration × iterations.

    The safeguarded forms reuse the values already fetched to detect oscillation and
    bisect with one lookup per step, so their count is the same upper bound.
    """
    start, per_iteration = LOOKUPS[estimator]
    return start + per_iteration * iterations


@dataclass(frozen=True)
class IterationStats:
    """Error statistics of one estimator after ``iteration`` iterations."""

    iteration: int
    mean_error_m: float
    p95_error_m: float
    max_error_m: float
    mean_error_texels: float
    p95_error_texels: float
    max_error_texels: float
    converged: float
    diverged: float
    lost: float


def _stats(values: np.ndarray) -> tuple[float, float, float]:
    if values.size == 0:
        return (float("nan"),) * 3
    return float(values.mean()), float(np.percentile(values, 95)), float(values.max())


def iteration_stats(estimates, lost, exact, texel_size, *,
                    tolerance_texels: float = 1.0) -> list[IterationStats]:
    """Statistics per iteration.

    Parameters
    ----------
    estimates : array (K+1, N)
        Estimated distance (m) after k = 0..K iterations.
    lost : array (K+1, N), bool
        The lookup at iteration k found no receiver.
    exact : array (N,)
        Exact distance (m), ``inf`` where the ray misses every receiver (those
        vertices are excluded: there is nothing to converge to).
    texel_size : float or array (N,)
        Footprint of one caustic-map texel at the exact hit, metres.
    """
    estimates = np.asarray(estimates, np.float64)
    lost = np.asarray(lost, bool)
    exact = np.asarray(exact, np.float64)
    if estimates.ndim != 2 or estimates.shape != lost.shape or estimates.shape[1] != exact.size:
        raise ValueError("estimates and lost must be (K+1, N) with N = len(exact)")
    texel = np.broadcast_to(np.asarray(texel_size, np.float64), exact.shape)
    valid = np.isfinite(exact)
    count = max(int(valid.sum()), 1)
    start_error = np.abs(estimates[0] - exact)
    rows = []
    for k in range(estimates.shape[0]):
        error = np.abs(estimates[k] - exact)
        finite = np.isfinite(error)
        ok = valid & ~lost[k] & finite
        texels = error / texel
        converged = ok & (texels <= tolerance_texels)
        diverged = valid & ~lost[k] & (~finite | ((texels > tolerance_texels)
                                                  & (error > start_error)))
        rows.append(IterationStats(
            k, *_stats(error[ok]), *_stats(texels[ok]),
            converged=float(converged.sum() / count),
            diverged=float(diverged.sum() / count),
            lost=float((valid & lost[k]).sum() / count),
        ))
    return rows
