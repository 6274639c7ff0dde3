"""What accuracy costs in time: (frame time, error) of many configurations of the
real-time method, the reference's own error-versus-time curve on the same axes, the
Pareto front and the equal-error speedup (``harness.studies.pareto``), warm against
warm (the headline) and cold against cold.

Error is the relMSE of receiver 0's caustic irradiance against the reference over
the caustic region, raw (``relmse``) and, given the reference's variance of the mean,
its excess over the reference's own noise (``noise``, ``excess`` with its standard
error and 95 % interval: :func:`harness.metrics.excess.excess_relative_mse` for the
method's configurations, :func:`harness.studies.reference_curve.budget_error` for the
reference's budgets); the speedup compares excesses (:mod:`harness.studies.pareto`).
Time is that of the passes producing the receiver maps (the
camera and shadow-map passes excluded), since the photon tracer it is compared
with produces only those maps. Configurations vary one thing at a time around the scene's
settings (grid, caustic-map size, splat width), plus every estimator at several
iteration counts. The reference curve is :mod:`harness.studies.reference_curve`.
Both sides are timed by one policy (:mod:`harness.studies.timing`): every row has
``time_warm_s`` and ``time_cold_s``. The reference's curve is fitted on warm times; the
cold speedup adds the reference's build and compile seconds to its fitted warm time
(t_cold = t_build + t_compile + t_warm), since on cold times the one-off seconds would
bend the curve away from a straight line in log-log.
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np
from scipy.special import ndtri

from harness.compare.evaluate import score_value
from harness.metrics.excess import excess_relative_mse
from harness.studies.pareto import (
    CONFIDENCE,
    CurveFit,
    CurveFitError,
    EqualErrorSpeedup,
    SpeedupUndefinedError,
    fit_cost_curve,
    pareto_front,
    speedup_from_fit,
)
from harness.studies.reference_curve import SEED_OFFSET, reference_curve
from harness.studies.runner import RealtimeRunner, caustic_seconds
from harness.studies.timing import TIMING_POLICY, OneOffCosts
from reports.records import Table

__all__ = ["COLUMNS", "CostOutcome", "cost_study", "sweep_configs"]

#: The cost table's columns: ``relmse`` is raw (against the reference); ``noise`` the
#: reference noise's expected share of it, ``excess`` the estimate against the noise-free
#: image with ``excess_stderr`` and the 95 % interval ``excess_low`` .. ``excess_high``
#: (model-based for the method, design-based for the reference's budgets; ``noise`` NaN
#: and ``excess`` = ``relmse`` without the reference's variance).
COLUMNS = ("series", "label", "estimator", "iterations", "grid", "caustic_map",
           "splat_sigma", "time_warm_s", "time_cold_s", "relmse", "pareto",
           "noise", "excess", "excess_stderr", "excess_low", "excess_high")


@dataclasses.dataclass(frozen=True)
class CostOutcome:
    """What the cost study found.

    Attributes
    ----------
    table : Table
        :data:`COLUMNS`, one row per configuration and reference budget.
    warm, cold : EqualErrorSpeedup or None
        Equal-error speedup of the scene's own settings, warm against warm and
        cold against cold, with its interval or bound (None where the curve cannot
        be fitted or the method's excess interval lies below 0).
    point : (float, float)
        That configuration's (warm time s, raw relMSE).
    fit : CurveFit or None
        The reference curve's log-log fit (slope and its standard error).
    method, reference : OneOffCosts
        Each side's build and compile seconds.
    """

    table: Table
    warm: EqualErrorSpeedup | None
    cold: EqualErrorSpeedup | None
    point: tuple[float, float]
    method: OneOffCosts
    reference: OneOffCosts
    fit: CurveFit | None = None

    def timing(self) -> dict:
        """The policy and both sides' one-off costs (for metrics.json)."""
        return {"policy": TIMING_POLICY, "method": self.method.as_dict(),
                "reference": self.reference.as_dict()}


def sweep_configs(*, quick: bool, splat: str = "points") -> list[dict]:
    """Settings overrides of the sweep (a smaller set when ``quick``): estimators x
    iterations, grid, map sizes, and the splat width (``points``) or the other
    kernels (``footprint``, ``triangles``; the Gaussian kernels without rim patches,
    which replace triangles) and, with triangles, the rim patches (none; 5 x 5)."""
    iterations = (0, 1, 3) if quick else (0, 1, 2, 3, 5, 8)
    grids = (32, 64, 128) if quick else (32, 64, 128, 256)
    maps = (256, 512) if quick else (256, 512, 1024)
    sigmas = (1.0, 2.0, 3.0)
    configs = [{"estimator": e, "iterations": k}
               for e in ("modified", "newton", "secant") for k in iterations]
    configs += [{"grid": g} for g in grids]
    configs += [{"caustic_map": m, "positions_map": m} for m in maps]
    if splat == "points":
        configs += [{"splat_sigma": s} for s in sigmas]
    else:
        configs += [{"splat": k} | ({} if k == "triangles" else {"rim_patches": 1})
                    for k in ("points", "footprint", "triangles") if k != splat]
    if splat == "triangles":
        configs += [{"rim_patches": n} for n in ((1,) if quick else (1, 5))]
    return configs


def sweep_size(settings, *, quick: bool) -> int:
    """Renders a :func:`cost_study` reports to its progress callable: every sweep
    configuration and every reference budget of the reference's curve."""
    return len(sweep_configs(quick=quick, splat=settings.splat)) + len(_fractions(quick))


def _fractions(quick: bool) -> tuple[int, ...]:
    """The reference curve's budgets, as fractions 1/n of the reference's photons."""
    return (64, 16, 4) if quick else (256, 64, 16, 4)


def _row(series: str, label: str, **values) -> dict:
    """One cost-table row by column name (``pareto`` is added once all rows exist)."""
    return {"series": series, "label": label, **values}


def _label(config: dict) -> str:
    return ", ".join(f"{k}={v}" for k, v in config.items() if k != "positions_map")


def _method_error(image: np.ndarray, reference: np.ndarray, caustic: np.ndarray, *,
                  variance, seeds, channel_correlation, seed_estimates=None) -> dict:
    """A configuration's raw relMSE and, with the reference's variance, its excess with
    the model-based interval (the method's image is fixed, the reference's noise is the
    randomness: :mod:`harness.metrics.excess`)."""
    if variance is None:
        raw = score_value("relmse", image, reference, mask=caustic, exposure=None)
        return {"relmse": raw, "noise": math.nan, "excess": raw, "excess_stderr": 0.0,
                "excess_low": raw, "excess_high": raw, "excess_dof": math.inf}
    e = excess_relative_mse(image, reference, variance, seeds=seeds, mask=caustic,
                            channel_correlation=channel_correlation,
                            seed_estimates=seed_estimates)
    return {"relmse": e.value, "noise": e.baseline, "excess": e.excess,
            "excess_stderr": e.excess_stderr, "excess_low": e.excess_ci95[0],
            "excess_high": e.excess_ci95[1], "excess_dof": e.degrees_of_freedom}


def _curve_interval(excess: float, stderr: float) -> tuple[float, float]:
    """A budget's normal 95 % interval (its design-based error has thousands of
    texels behind it)."""
    half = float(ndtri(0.5 + CONFIDENCE / 2)) * stderr
    return excess - half, excess + half


def cost_study(runner: RealtimeRunner, reference: np.ndarray, caustic: np.ndarray, *,
               reference_photons: int, quick: bool = False, progress=None,
               reference_variance: np.ndarray | None = None,
               reference_seeds: int | None = None,
               channel_correlation: float = 1.0,
               reference_seed_maps: np.ndarray | None = None) -> CostOutcome:
    """Sweep the method's configurations and trace the reference's curve.

    Parameters
    ----------
    reference, caustic
        Reference caustic irradiance of receiver 0 (W/m², (H, W, 3)) and its caustic
        region ((H, W) bool).
    reference_photons
        Photons per seed of the reference; the curve uses 1/256 .. 1/4 of it
        (1/64 .. 1/4 when ``quick``).
    reference_variance : ndarray (H, W, 3), optional
        The reference's variance of the mean per texel and channel ((W/m²)²). With it
        both sides' errors are corrected for the reference's noise (module docstring);
        without it they are raw and the speedup's interval covers the fit alone.
    reference_seeds : int, optional
        K, the seeds behind ``reference_variance`` (required with it).
    channel_correlation : float
        1 when the same photons carry all three channels, 0 for one pass per channel.
    reference_seed_maps : ndarray (K, H, W, 3), optional
        The reference's per-seed maps: the method rows' excess uses them as the
        comparison's records do (``harness.metrics.excess``), so the scene-settings
        row quotes the record's number.
    """
    if reference_variance is not None and reference_seeds is None:
        raise ValueError("reference_variance needs reference_seeds")
    noise_model = {"variance": reference_variance, "seeds": reference_seeds,
                   "channel_correlation": channel_correlation}
    s = runner.settings
    rows, warm_times, dofs = [], [], []
    configs = [({}, "scene settings"), *((c, _label(c)) for c in sweep_configs(
        quick=quick, splat=s.splat))]
    for config, label in configs:
        frame, seconds = runner.timed(clock=caustic_seconds, **config)
        error = _method_error(frame.result.receivers[0].irradiance, reference, caustic,
                              **noise_model, seed_estimates=reference_seed_maps)
        dofs.append(error.pop("excess_dof"))
        merged = {"estimator": s.estimator, "iterations": s.iterations, "grid": s.grid,
                  "caustic_map": s.caustic_map, "splat_sigma": s.splat_sigma, **config}
        rows.append(_row("caustics_mapping", label, **merged, **error))
        warm_times.append(seconds)
        if config and progress is not None:
            progress()
    method = runner.one_off(clock=caustic_seconds)
    for row, warm in zip(rows, warm_times, strict=True):
        row.update(time_warm_s=warm, time_cold_s=method.cold(warm))
    budgets = [max(1, reference_photons // f) for f in _fractions(quick)]
    curve = reference_curve(runner.scene, reference, caustic, budgets=budgets,
                            repeats=runner.repeats, seed=s.seed + SEED_OFFSET,
                            progress=progress, **noise_model)
    for p in curve.points:
        low, high = _curve_interval(p.excess, p.excess_stderr)
        rows.append(_row("reference", f"photons={p.photons}", estimator="", iterations=0,
                         grid=0, caustic_map=0, splat_sigma=0.0, time_warm_s=p.time_warm_s,
                         time_cold_s=p.time_cold_s, relmse=p.relmse, noise=p.noise,
                         excess=p.excess, excess_stderr=p.excess_stderr, excess_low=low,
                         excess_high=high))
    # The caustics-mapping rows come first, so front indices are row indices. The
    # front is on raw relMSE, the axis the cost figure draws.
    realtime = [r for r in rows if r["series"] == "caustics_mapping"]
    front = set(pareto_front([r["time_warm_s"] for r in realtime],
                             [r["relmse"] for r in realtime]).tolist())
    table = Table.from_records(COLUMNS, [{**row, "pareto": i in front}
                                         for i, row in enumerate(rows)])
    base = rows[0]
    speedups: dict[str, EqualErrorSpeedup | None] = {"warm": None, "cold": None}
    try:
        fit = fit_cost_curve([p.time_warm_s for p in curve.points],
                             [p.excess for p in curve.points],
                             [p.excess_stderr for p in curve.points])
    except CurveFitError:
        fit = None
    if fit is not None:
        overheads = {"warm": 0.0, "cold": curve.one_off.build_s + curve.one_off.compile_s}
        for kind, overhead in overheads.items():
            t = base[f"time_{kind}_s"]
            if not (t > 0 and math.isfinite(base["excess"])):
                continue
            try:
                speedups[kind] = speedup_from_fit(
                    t, base["excess"], fit, method_stderr=base["excess_stderr"],
                    method_dof=dofs[0], overhead_s=overhead)
            except (SpeedupUndefinedError, CurveFitError):
                speedups[kind] = None
    return CostOutcome(table=table, warm=speedups["warm"], cold=speedups["cold"],
                       point=(base["time_warm_s"], base["relmse"]), method=method,
                       reference=curve.one_off, fit=fit)
