"""The reference's own error-versus-time curve, sampled and timed as the reference
and the method are.

The curve traces the photon tracer the reference uses (``caustic_only``: every
photon aimed at a specular object, the same emission as the cached reference) with
growing photon budgets, on seeds disjoint from the reference's, and scores each
budget's receiver-0 caustic map against the reference (relMSE over the caustic
region). One tracer serves every budget: the Mitsuba scene and its acceleration
structure are built once (``t_build``), and the photon kernel compiles once for
every launch size (``t_compile``). Times follow :mod:`harness.studies.timing`.

Noise correction. Scored against the K-seed reference R, a budget b's relMSE is
e(b) ≈ c/b + n_R, with n_R ≈ mean w v the share of R's own variance of the mean v
(w = 1/(R² + ε)): the same for every budget, so the raw curve flattens towards n_R.
With R's variance, each point also gets its *excess* (:func:`budget_error`: the
estimate of the budget's relMSE against the noise-free image,
:func:`harness.metrics.excess.excess_relative_mse`), the quantity the method's excess
is compared with (:mod:`harness.studies.pareto`).

A point's standard error is design-based: the budget's map is itself a Monte Carlo
estimate, and the texels' noises are independent (each photon lands in one texel), so
the spread of the per-texel excess terms T_i (channels summed) over the n texels of the
region gives Var(excess) ≈ n s²(T_i) / (3n)². That covers the budget's own noise and R's
(the model-based error of ``excess_relative_mse`` covers R's alone). The spread of the
texels' expected terms (brighter texels have more photons) adds to s², so the error is
on the safe side.
"""

from __future__ import annotations

import dataclasses
import time

import numpy as np

from harness.compare.evaluate import score_value
from harness.metrics.excess import excess_relative_mse, relmse_variance_terms
from harness.metrics.scores import RELMSE_EPSILON
from harness.studies.timing import OneOffCosts, median_seconds
from renderers.mitsuba import load_mitsuba
from renderers.mitsuba.photons import PhotonTracer
from scenes import Scene

__all__ = ["BudgetError", "CurvePoint", "ReferenceCurve", "budget_error", "reference_curve"]

#: Seeds of the curve start here above the scene's seed: disjoint from the
#: reference's (seed .. seed + K - 1) and the independent reference's (.. + 2K - 1).
SEED_OFFSET = 10_000


@dataclasses.dataclass(frozen=True)
class CurvePoint:
    """One budget of the curve.

    Attributes
    ----------
    photons : int
        Photons traced (per channel pass).
    time_warm_s, time_cold_s : float
        Seconds (:mod:`harness.studies.timing`).
    relmse : float
        Raw error of the budget's caustic map against the reference.
    noise, excess, excess_stderr : float
        :class:`BudgetError`'s fields.
    """

    photons: int
    time_warm_s: float
    time_cold_s: float
    relmse: float
    noise: float
    excess: float
    excess_stderr: float


@dataclasses.dataclass(frozen=True)
class BudgetError:
    """A budget's relMSE over the caustic region, raw and noise-corrected.

    Attributes
    ----------
    relmse : float
        Against the reference R (raw).
    noise : float
        The expected raw relMSE of the noise-free image against R, mean w v (NaN
        without R's variance: nothing subtracted).
    excess : float
        Estimate of the budget's relMSE against the noise-free image (``relmse``
        itself without R's variance).
    excess_stderr : float
        Design-based standard error of ``excess`` (module docstring).
    """

    relmse: float
    noise: float
    excess: float
    excess_stderr: float


@dataclasses.dataclass(frozen=True)
class ReferenceCurve:
    """The curve's points (increasing budget) and the tracer's one-off costs."""

    points: tuple[CurvePoint, ...]
    one_off: OneOffCosts


def budget_error(image: np.ndarray, reference: np.ndarray, caustic: np.ndarray, *,
                 variance: np.ndarray | None = None, seeds: int | None = None,
                 channel_correlation: float = 1.0) -> BudgetError:
    """Score one budget's map (module docstring: the correction and the standard error).

    Parameters
    ----------
    image, reference : ndarray (H, W, 3)
        The budget's and the reference's caustic irradiance (W/m²).
    caustic : ndarray (H, W) of bool
        The region.
    variance : ndarray (H, W, 3), optional
        The reference's variance of the mean per texel and channel ((W/m²)²); without
        it the point is left uncorrected.
    seeds : int, optional
        K, the seeds behind ``variance`` (required with it).
    channel_correlation : float
        1 when the same photons carry all three channels, 0 for one pass per channel.
    """
    mask = np.asarray(caustic, bool)
    if variance is None:
        relmse = score_value("relmse", image, reference, mask=caustic, exposure=None)
        m = np.asarray(image, np.float64)
        r = np.asarray(reference, np.float64)
        terms = (m - r) ** 2 / (r * r + RELMSE_EPSILON)
        noise, excess = float("nan"), relmse
    else:
        if seeds is None:
            raise ValueError("the reference's variance needs its seed count")
        scored = excess_relative_mse(image, reference, variance, seeds=seeds, mask=mask,
                                     channel_correlation=channel_correlation)
        terms = relmse_variance_terms(image, reference, variance, seeds=seeds,
                                      channel_correlation=channel_correlation)[0]
        relmse, noise, excess = scored.value, scored.baseline, scored.excess
    per_texel = terms[mask].sum(axis=-1)
    count = terms[mask].size
    n = per_texel.size
    stderr = (float(np.sqrt(n * np.var(per_texel, ddof=1))) / count if n > 1
              else float("nan"))
    return BudgetError(relmse=float(relmse), noise=noise, excess=float(excess),
                       excess_stderr=stderr)


def reference_curve(scene: Scene, reference: np.ndarray, caustic: np.ndarray, *,
                    budgets: list[int], repeats: int, seed: int, progress=None,
                    variance: np.ndarray | None = None, seeds: int | None = None,
                    channel_correlation: float = 1.0) -> ReferenceCurve:
    """Trace and time ``budgets`` (photons per channel pass, increasing).

    Parameters
    ----------
    reference : ndarray (H, W, 3)
        The reference's receiver-0 caustic irradiance (W/m²), at the map size the
        scene's settings give (``receiver_map``).
    caustic : ndarray (H, W) of bool
        The caustic region the error is taken over.
    repeats : int
        Timed runs per budget, after one untimed warm-up of the same budget.
    seed : int
        The curve's first seed (budget i uses ``seed + i``).
    progress : callable, optional
        Called once per budget.
    variance, seeds, channel_correlation
        The reference's variance of the mean and its seeds (:func:`budget_error`).
    """
    _, dr, _ = load_mitsuba()
    # As in a fresh process: no kernel resident in memory (rendering the reference
    # in this process left them there); Dr.Jit's on-disk cache stays, as Mesa's
    # shader cache does for the method's fresh GL context.
    dr.flush_kernel_cache()
    start = time.perf_counter()
    tracer = PhotonTracer(scene, caustic_only=True)
    build = time.perf_counter() - start
    points, compile_s = [], None
    for i, photons in enumerate(budgets):
        sums, first, warm = median_seconds(
            lambda n=photons, k=seed + i: tracer.trace(n, seed=k), repeats=repeats)
        if compile_s is None:  # the first launch in this process: the kernel compiles
            compile_s = max(first - warm, 0.0)
        error = budget_error(sums.caustic[0] / sums.photons, reference, caustic,
                             variance=variance, seeds=seeds,
                             channel_correlation=channel_correlation)
        points.append((sums.photons, warm, error))
        if progress is not None:
            progress()
    one_off = OneOffCosts(build_s=build, compile_s=compile_s or 0.0)
    return ReferenceCurve(
        points=tuple(CurvePoint(photons=n, time_warm_s=warm, time_cold_s=one_off.cold(warm),
                                relmse=error.relmse, noise=error.noise, excess=error.excess,
                                excess_stderr=error.excess_stderr)
                     for n, warm, error in points),
        one_off=one_off)
