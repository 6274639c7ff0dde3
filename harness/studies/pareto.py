"""Pareto fronts of (time, error) points and the equal-error speedup.

A configuration of the real-time method (estimator, iterations, grid, map size,
splat radius) is one point (t, e): its frame time and its error against the
reference. The reference's own error-versus-time curve comes from rendering it with
growing budgets and scoring each against an independent converged seed.

Equal-error speedup: the time the reference needs to reach the real-time method's
error, divided by the real-time method's time,

    S = t_ref(e_method) / t_method,

with t_ref(e) interpolated linearly in log-log space between measured budgets. Below
the smallest measured reference error we extrapolate with the Monte Carlo rate
relMSE ∝ 1/t (slope -1 in log-log); above the largest we report only the bound
S ≤ t_ref,min / t_method. The result says which of the three applied.
"""

from __future__ import annotations

import numpy as np

from reports.records import EqualErrorSpeedup

__all__ = ["EqualErrorSpeedup", "equal_error_speedup", "pareto_front"]


def pareto_front(times, errors) -> np.ndarray:
    """Indices of the points not dominated in (time, error), sorted by time.

    A point is dominated when another is no slower and no less accurate, and
    strictly better in one of the two. Non-finite points are never on the front.
    """
    times = np.asarray(times, float)
    errors = np.asarray(errors, float)
    if times.shape != errors.shape or times.ndim != 1:
        raise ValueError("times and errors must be 1-D arrays of equal length")
    ok = np.flatnonzero(np.isfinite(times) & np.isfinite(errors))
    order = ok[np.lexsort((errors[ok], times[ok]))]
    front, best = [], np.inf
    for i in order:
        if errors[i] < best:
            front.append(i)
            best = errors[i]
    return np.asarray(front, dtype=int)


def equal_error_speedup(method_time: float, method_error: float, reference_times,
                        reference_errors) -> EqualErrorSpeedup:
    """Equal-error speedup of a real-time point (``method_time`` s, ``method_error``) over the
    reference's (time, error) curve. Errors must be positive (relMSE-like)."""
    t = np.asarray(reference_times, float)
    e = np.asarray(reference_errors, float)
    if t.size < 1 or t.shape != e.shape:
        raise ValueError("need at least one reference point with matching times and errors")
    if not (method_time > 0 and method_error > 0 and np.all(t > 0) and np.all(e > 0)):
        raise ValueError("times and errors must be positive")
    # The error of a converging reference falls with time: keep its lower envelope.
    front = pareto_front(t, e)
    t, e = t[front], e[front]
    if method_error >= e[0]:
        return EqualErrorSpeedup(t[0] / method_time, float(t[0]), "bound")
    if method_error < e[-1]:
        # relMSE ∝ 1/t: t(e) = t_last · e_last / e.
        t_needed = t[-1] * e[-1] / method_error
        return EqualErrorSpeedup(t_needed / method_time, float(t_needed), "extrapolated")
    log_t, log_e = np.log(t), np.log(e)
    # e decreases along the front; np.interp needs increasing x, so reverse.
    t_needed = float(np.exp(np.interp(np.log(method_error), log_e[::-1], log_t[::-1])))
    return EqualErrorSpeedup(t_needed / method_time, t_needed, "interpolated")
