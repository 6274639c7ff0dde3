"""Pareto fronts of (time, error) points and the equal-error speedup with its interval.

A configuration of the real-time method (estimator, iterations, grid, map size,
splat radius) is one point (t, e): its frame time and its error. The reference's own
error-versus-time curve comes from rendering it with growing budgets
(:mod:`harness.studies.reference_curve`).

Errors are *excess* relMSEs (:mod:`harness.metrics.excess`): each side's relMSE against
the noise-free image, estimated from its raw relMSE against the K-seed reference R
minus the share R's own noise contributes (about mean w v over the region). Without
that correction every curve point carries the same n_R, e(b) ≈ c/b + n_R, and the curve
flattens towards n_R instead of falling as the budget's own noise does.

The curve's fit. Over its points j (warm time t_j, excess e_j with standard error σ_j)

    log e_j = a + s log t_j,

by weighted least squares with weights 1 / (σ_j / e_j)² (the delta method's variance
of log e_j), so Cov(a, s) = (Xᵀ W X)⁻¹, scaled by max(1, χ² / (n − 2)) (Birge's ratio:
the points' standard errors do not see a curve that is not a straight line in log-log,
e.g. a per-launch overhead in the time). s is reported with its standard error; the
Monte Carlo rate alone would give s = −1.

Equal-error speedup. The reference's time to reach error e is the fit's inverse,
t_ref(e) = exp((log e − a) / s), plus ``overhead_s`` (the reference's build and compile
seconds for a cold-against-cold speedup; the fit is always on warm times), and

    S = t_ref(e_method) / t_method.

Interval: a parametric bootstrap of :data:`DRAWS` draws, (a, s) from the fit's normal
(slopes ≥ 0 rejected: a curve that does not fall reaches no error) and e_method from
its estimate ± its standard error times Student's t; the 2.5 and 97.5 % quantiles of
S (a draw of e_method ≤ 0 needs an infinite reference time). The result says which case
applied (``bound_kind``):

* ``"estimate"``: the method's excess interval lies above 0; ``kind`` is
  ``"interpolated"`` within the curve's errors, ``"extrapolated"`` below them;
* ``"lower bound"``: the interval contains 0, the method is not measurably off the
  truth and S has no finite upper end; the reference needs at least t_ref(e_high), so
  S ≥ the 2.5 % quantile of t_ref(e_high) / t_method over the fit's draws (e_high is
  the excess's 97.5 % limit: both one-sided 2.5 % risks together, ≥ 95 % confidence);
* ``"upper bound"`` (``kind == "bound"``): the curve's cheapest budget is already more
  accurate than the method, so S ≤ t_ref,min / t_method.
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np
from scipy.special import stdtrit

from reports.records import EqualErrorSpeedup

__all__ = ["DRAWS", "CurveFit", "CurveFitError", "EqualErrorSpeedup", "SpeedupUndefinedError",
           "equal_error_speedup", "fit_cost_curve", "pareto_front", "speedup_from_fit"]

#: Parametric-bootstrap draws of the speedup's interval: the 2.5 % quantile of 4000
#: draws has a Monte Carlo standard error of sqrt(0.025 · 0.975 / 4000) ≈ 0.25 %
#: in probability, small against the interval's own 95 %.
DRAWS = 4000
#: Two-sided confidence of every interval here.
CONFIDENCE = 0.95


class CurveFitError(ValueError):
    """The reference's curve cannot be fitted: too few usable points, or an error that
    does not fall with time."""


class SpeedupUndefinedError(ValueError):
    """No speedup or bound can be given: the method's excess interval lies wholly below
    0 (the reference's variance is overstated; :mod:`harness.metrics.excess`)."""


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


@dataclasses.dataclass(frozen=True)
class CurveFit:
    """log e = a + s log t fitted to the reference's curve (module docstring).

    Attributes
    ----------
    intercept, slope : float
        a (log relMSE at t = 1 s) and s.
    covariance : tuple of tuple of float
        Cov(a, s), 2 x 2, Birge-scaled; NaN where it cannot be estimated (two points
        without standard errors).
    chi2 : float
        Weighted residual sum of squares (NaN without standard errors).
    dof : int
        Points − 2.
    times, errors : tuple of float
        The fitted points (s, relMSE), increasing time.
    """

    intercept: float
    slope: float
    covariance: tuple[tuple[float, float], tuple[float, float]]
    chi2: float
    dof: int
    times: tuple[float, ...]
    errors: tuple[float, ...]

    @property
    def slope_stderr(self) -> float:
        """Standard error of ``slope``."""
        return math.sqrt(self.covariance[1][1])

    def slope_interval(self) -> tuple[float, float]:
        """95 % interval of the slope (normal: the points' variances are taken as known)."""
        half = float(stdtrit(math.inf, 0.5 + CONFIDENCE / 2)) * self.slope_stderr
        return self.slope - half, self.slope + half

    def time_at(self, error: float) -> float:
        """t_ref(e) on the fitted line (s); infinite for e ≤ 0."""
        if not error > 0:
            return math.inf
        return math.exp((math.log(error) - self.intercept) / self.slope)


def fit_cost_curve(times, errors, stderrs=None) -> CurveFit:
    """Fit log e = a + s log t by weighted least squares (module docstring).

    Parameters
    ----------
    times : sequence of float
        Warm seconds of each budget.
    errors : sequence of float
        Excess relMSE of each budget; non-positive or non-finite points are left out.
    stderrs : sequence of float, optional
        Standard errors of ``errors``. Without them the points weigh equally and the
        covariance comes from the residuals alone (NaN with two points).
    """
    t = np.asarray(times, float)
    e = np.asarray(errors, float)
    se = np.ones_like(e) if stderrs is None else np.asarray(stderrs, float)
    if t.shape != e.shape or se.shape != e.shape or t.ndim != 1:
        raise CurveFitError("times, errors and standard errors must be 1-D of equal length")
    ok = np.isfinite(t) & np.isfinite(e) & np.isfinite(se) & (t > 0) & (e > 0)
    if stderrs is not None:
        ok &= se > 0
    if ok.sum() < 2:
        raise CurveFitError(f"need two points with positive time and error, got {ok.sum()}")
    t, e, se = t[ok], e[ok], se[ok]
    order = np.argsort(t)
    t, e, se = t[order], e[order], se[order]
    x, y = np.log(t), np.log(e)
    # Delta method: SE(log e) = SE(e) / e.
    weight = np.ones_like(y) if stderrs is None else (e / se) ** 2
    design = np.stack([np.ones_like(x), x], axis=1)
    normal = design.T @ (weight[:, None] * design)
    inverse = np.linalg.inv(normal)
    intercept, slope = inverse @ (design.T @ (weight * y))
    residual = y - intercept - slope * x
    chi2 = float(np.sum(weight * residual**2))
    dof = int(t.size - 2)
    if stderrs is None:
        scale = chi2 / dof if dof > 0 else math.nan
        chi2 = math.nan
    else:
        scale = max(1.0, chi2 / dof) if dof > 0 else 1.0
    if not slope < 0:
        raise CurveFitError(f"the reference's error does not fall with time (slope {slope:.3g})")
    cov = inverse * scale
    return CurveFit(intercept=float(intercept), slope=float(slope),
                    covariance=((float(cov[0, 0]), float(cov[0, 1])),
                                (float(cov[1, 0]), float(cov[1, 1]))),
                    chi2=chi2, dof=dof, times=tuple(t.tolist()), errors=tuple(e.tolist()))


def _fit_draws(fit: CurveFit, rng: np.random.Generator, draws: int) -> np.ndarray | None:
    """(draws, 2) samples of (a, s) from the fit's normal with s < 0, or None when the
    covariance is unknown."""
    cov = np.asarray(fit.covariance)
    if not np.isfinite(cov).all():
        return None
    mean = np.array([fit.intercept, fit.slope])
    kept = np.empty((0, 2))
    for _ in range(100):  # rejection of s ≥ 0; one round unless s is within ~2 SE of 0
        sample = rng.multivariate_normal(mean, cov, size=draws, method="svd")
        kept = np.concatenate([kept, sample[sample[:, 1] < 0]])
        if len(kept) >= draws:
            return kept[:draws]
    raise CurveFitError("the fitted slope is not distinguishable from 0")


def _log_times(log_error: np.ndarray, params: np.ndarray) -> np.ndarray:
    """log t_ref for each (log e, (a, s)) draw; +inf where e ≤ 0 (log e = −inf)."""
    with np.errstate(invalid="ignore"):
        out = (log_error - params[:, 0]) / params[:, 1]
    return np.where(np.isneginf(log_error), np.inf, out)


def _quantile(values: np.ndarray, q: float) -> float:
    # inverted_cdf picks a sample, so infinite draws (e ≤ 0) do not turn into NaN.
    return float(np.quantile(values, q, method="inverted_cdf"))


def speedup_from_fit(method_time: float, method_error: float, fit: CurveFit, *,
                     method_stderr: float = 0.0, method_dof: float = math.inf,
                     overhead_s: float = 0.0, draws: int = DRAWS,
                     rng: np.random.Generator | None = None) -> EqualErrorSpeedup:
    """Equal-error speedup of a real-time point over a fitted reference curve, with its
    95 % interval or the bound that applies (module docstring).

    Parameters
    ----------
    method_time : float
        The method's seconds (warm, or cold with ``overhead_s`` the reference's
        one-off seconds).
    method_error, method_stderr, method_dof : float
        The method's excess relMSE, its standard error and the degrees of freedom of
        that error (:class:`harness.metrics.excess.ExcessError`); a standard error of 0
        takes the error as exact.
    overhead_s : float
        Seconds added to every reference time (build and compile, for cold).
    rng : numpy.random.Generator, optional
        The bootstrap's generator (default: seeded with 0, so a result is reproducible).
    """
    if not (method_time > 0 and math.isfinite(method_error) and method_stderr >= 0):
        raise ValueError("the method's time must be positive, its error finite and its "
                         "standard error non-negative")
    rng = np.random.default_rng(0) if rng is None else rng
    quantile = float(stdtrit(method_dof, 0.5 + CONFIDENCE / 2))
    low_e, high_e = method_error - quantile * method_stderr, method_error + quantile * method_stderr
    if not high_e > 0:
        raise SpeedupUndefinedError(
            f"the method's excess interval ({low_e:.3g}, {high_e:.3g}) has no positive "
            "error: no reference time corresponds to it")
    alpha = (1.0 - CONFIDENCE) / 2
    params = _fit_draws(fit, rng, draws)
    common = {"slope": fit.slope, "slope_stderr": fit.slope_stderr}
    cheapest_time, cheapest_error = fit.times[0], fit.errors[0]
    within = min(fit.errors) <= high_e <= max(fit.errors)

    if not low_e > 0:
        # Not measurably off the truth: only "the reference needs at least t_ref(e_high)".
        if params is None:
            bound = fit.time_at(high_e) + overhead_s
        else:
            log_t = _log_times(np.full(len(params), math.log(high_e)), params)
            bound = math.exp(_quantile(log_t, alpha)) + overhead_s
        return EqualErrorSpeedup(bound / method_time, bound,
                                 "interpolated" if within else "extrapolated",
                                 low=bound / method_time, high=math.inf,
                                 bound_kind="lower bound", **common)
    if method_error >= cheapest_error:
        bound = cheapest_time + overhead_s
        return EqualErrorSpeedup(bound / method_time, bound, "bound", high=bound / method_time,
                                 bound_kind="upper bound", **common)
    kind = "extrapolated" if method_error < min(fit.errors) else "interpolated"
    t_needed = fit.time_at(method_error) + overhead_s
    low = high = math.nan
    if params is not None:
        spread = rng.standard_t(method_dof, size=len(params)) if math.isfinite(method_dof) \
            else rng.standard_normal(len(params))
        error_draws = method_error + method_stderr * spread
        with np.errstate(divide="ignore", invalid="ignore"):
            log_error = np.where(error_draws > 0, np.log(error_draws), -np.inf)
        times = np.exp(_log_times(log_error, params)) + overhead_s
        low, high = _quantile(times, alpha) / method_time, _quantile(times, 1 - alpha) / method_time
    return EqualErrorSpeedup(t_needed / method_time, t_needed, kind, low=low, high=high,
                             bound_kind="estimate", **common)


def equal_error_speedup(method_time: float, method_error: float, reference_times,
                        reference_errors, *, reference_stderrs=None,
                        method_stderr: float = 0.0, method_dof: float = math.inf,
                        overhead_s: float = 0.0,
                        rng: np.random.Generator | None = None) -> EqualErrorSpeedup:
    """Equal-error speedup of a real-time point (``method_time`` s, ``method_error``)
    over the reference's (warm time, excess error) points: :func:`fit_cost_curve` then
    :func:`speedup_from_fit` (their parameters)."""
    fit = fit_cost_curve(reference_times, reference_errors, reference_stderrs)
    return speedup_from_fit(method_time, method_error, fit, method_stderr=method_stderr,
                            method_dof=method_dof, overhead_s=overhead_s, rng=rng)
