"""The reference's own error-versus-time curve, sampled and timed as the reference
and the method are.

The curve traces the photon tracer the reference uses (``caustic_only``: every
photon aimed at a specular object, the same emission as the cached reference) with
growing photon budgets, on seeds disjoint from the reference's, and scores each
budget's receiver-0 caustic map against the reference (relMSE over the caustic
region). One tracer serves every budget: the Mitsuba scene and its acceleration
structure are built once (``t_build``), and the photon kernel compiles once for
every launch size (``t_compile``). Times follow :mod:`harness.studies.timing`.
"""

from __future__ import annotations

import dataclasses
import time

import numpy as np

from harness.compare.evaluate import score_value
from harness.studies.timing import OneOffCosts, median_seconds
from renderers.mitsuba import load_mitsuba
from renderers.mitsuba.photons import PhotonTracer
from scenes import Scene

__all__ = ["CurvePoint", "ReferenceCurve", "reference_curve"]

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
        Error of the budget's caustic map against the reference.
    """

    photons: int
    time_warm_s: float
    time_cold_s: float
    relmse: float


@dataclasses.dataclass(frozen=True)
class ReferenceCurve:
    """The curve's points (increasing budget) and the tracer's one-off costs."""

    points: tuple[CurvePoint, ...]
    one_off: OneOffCosts


def reference_curve(scene: Scene, reference: np.ndarray, caustic: np.ndarray, *,
                    budgets: list[int], repeats: int, seed: int, progress=None,
                    ) -> ReferenceCurve:
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
        error = score_value("relmse", sums.caustic[0] / sums.photons, reference,
                            mask=caustic, exposure=None)
        points.append((sums.photons, warm, error))
        if progress is not None:
            progress()
    one_off = OneOffCosts(build_s=build, compile_s=compile_s or 0.0)
    return ReferenceCurve(
        points=tuple(CurvePoint(photons=n, time_warm_s=warm, time_cold_s=one_off.cold(warm),
                                relmse=error) for n, warm, error in points),
        one_off=one_off)
