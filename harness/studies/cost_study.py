"""What accuracy costs in time: (frame time, error) of many configurations of the
real-time method, the reference's own error-versus-time curve on the same axes, the
Pareto front and the equal-error speedup (``harness.studies.pareto``), warm against
warm (the headline) and cold against cold.

Error is the relMSE of receiver 0's caustic irradiance against the reference over
the caustic region; time is that of the passes producing the receiver maps (the
camera and shadow-map passes excluded), since the photon tracer it is compared
with produces only those maps. Configurations vary one thing at a time around the scene's
settings (grid, caustic-map size, splat width), plus every estimator at several
iteration counts. The reference curve is :mod:`harness.studies.reference_curve`.
Both sides are timed by one policy (:mod:`harness.studies.timing`): every row has
``time_warm_s`` and ``time_cold_s``.
"""

from __future__ import annotations

import dataclasses

import numpy as np

from harness.compare.evaluate import score_value
from harness.studies.pareto import EqualErrorSpeedup, equal_error_speedup, pareto_front
from harness.studies.reference_curve import SEED_OFFSET, reference_curve
from harness.studies.runner import RealtimeRunner, caustic_seconds
from harness.studies.timing import TIMING_POLICY, OneOffCosts
from reports.records import Table

__all__ = ["COLUMNS", "CostOutcome", "cost_study", "sweep_configs"]

COLUMNS = ("series", "label", "estimator", "iterations", "grid", "caustic_map",
           "splat_sigma", "time_warm_s", "time_cold_s", "relmse", "pareto")


@dataclasses.dataclass(frozen=True)
class CostOutcome:
    """What the cost study found.

    Attributes
    ----------
    table : Table
        :data:`COLUMNS`, one row per configuration and reference budget.
    warm, cold : EqualErrorSpeedup or None
        Equal-error speedup of the scene's own settings, warm against warm and
        cold against cold (None where an error is zero).
    point : (float, float)
        That configuration's (warm time s, relMSE).
    method, reference : OneOffCosts
        Each side's build and compile seconds.
    """

    table: Table
    warm: EqualErrorSpeedup | None
    cold: EqualErrorSpeedup | None
    point: tuple[float, float]
    method: OneOffCosts
    reference: OneOffCosts

    def timing(self) -> dict:
        """The policy and both sides' one-off costs (for metrics.json)."""
        return {"policy": TIMING_POLICY, "method": self.method.as_dict(),
                "reference": self.reference.as_dict()}


def sweep_configs(*, quick: bool, splat: str = "points") -> list[dict]:
    """Settings overrides of the sweep (a smaller set when ``quick``): estimators x
    iterations, grid, map sizes, and the splat width (``points``) or the other
    kernels (``footprint``, ``triangles``)."""
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
        configs += [{"splat": k} for k in ("points", "footprint", "triangles") if k != splat]
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


def cost_study(runner: RealtimeRunner, reference: np.ndarray, caustic: np.ndarray, *,
               reference_photons: int, quick: bool = False, progress=None) -> CostOutcome:
    """Sweep the method's configurations and trace the reference's curve.

    Parameters
    ----------
    reference, caustic
        Reference caustic irradiance of receiver 0 (W/m²) and its caustic region.
    reference_photons
        Photons per seed of the reference; the curve uses 1/256 .. 1/4 of it
        (1/64 .. 1/4 when ``quick``).
    """
    s = runner.settings
    rows, warm_times = [], []
    configs = [({}, "scene settings"), *((c, _label(c)) for c in sweep_configs(
        quick=quick, splat=s.splat))]
    for config, label in configs:
        frame, seconds = runner.timed(clock=caustic_seconds, **config)
        error = score_value("relmse", frame.result.receivers[0].irradiance, reference,
                            mask=caustic, exposure=None)
        merged = {"estimator": s.estimator, "iterations": s.iterations, "grid": s.grid,
                  "caustic_map": s.caustic_map, "splat_sigma": s.splat_sigma, **config}
        rows.append(_row("caustics_mapping", label, **merged, relmse=error))
        warm_times.append(seconds)
        if config and progress is not None:
            progress()
    method = runner.one_off(clock=caustic_seconds)
    for row, warm in zip(rows, warm_times, strict=True):
        row.update(time_warm_s=warm, time_cold_s=method.cold(warm))
    budgets = [max(1, reference_photons // f) for f in _fractions(quick)]
    curve = reference_curve(runner.scene, reference, caustic, budgets=budgets,
                            repeats=runner.repeats, seed=s.seed + SEED_OFFSET,
                            progress=progress)
    for p in curve.points:
        rows.append(_row("reference", f"photons={p.photons}", estimator="", iterations=0,
                         grid=0, caustic_map=0, splat_sigma=0.0, time_warm_s=p.time_warm_s,
                         time_cold_s=p.time_cold_s, relmse=p.relmse))
    # The caustics-mapping rows come first, so front indices are row indices.
    realtime = [r for r in rows if r["series"] == "caustics_mapping"]
    front = set(pareto_front([r["time_warm_s"] for r in realtime],
                             [r["relmse"] for r in realtime]).tolist())
    table = Table.from_records(COLUMNS, [{**row, "pareto": i in front}
                                         for i, row in enumerate(rows)])
    base = rows[0]
    errors = [p.relmse for p in curve.points]
    speedups = {}
    for kind in ("warm", "cold"):
        t = base[f"time_{kind}_s"]
        speedups[kind] = (equal_error_speedup(t, base["relmse"],
                                              [getattr(p, f"time_{kind}_s") for p in curve.points],
                                              errors)
                          if t > 0 and base["relmse"] > 0 and all(e > 0 for e in errors)
                          else None)
    return CostOutcome(table=table, warm=speedups["warm"], cold=speedups["cold"],
                       point=(base["time_warm_s"], base["relmse"]), method=method,
                       reference=curve.one_off)
