"""What accuracy costs in time: (frame time, error) of many configurations of the
real-time method, the reference's own error-versus-time curve on the same axes, the
Pareto front and the equal-error speedup (``harness.studies.pareto``).

Error is the relMSE of receiver 0's caustic irradiance against the reference over
the caustic region; time is that of the passes producing the receiver maps (the
camera and shadow-map passes excluded), since the photon tracer it is compared
with produces only those maps. Configurations vary one thing at a time around the scene's
settings (grid, caustic-map size, splat width), plus every estimator at several
iteration counts. The reference curve renders the photon tracer with growing photon
budgets on a seed disjoint from the reference's and times it end to end
(``time.perf_counter``, kernel compilation included: that is what it costs).
"""

from __future__ import annotations

import statistics

import numpy as np

from harness.compare.evaluate import score_value
from harness.studies.pareto import EqualErrorSpeedup, equal_error_speedup, pareto_front
from harness.studies.runner import RealtimeRunner, caustic_seconds
from renderers.mitsuba.reference import estimate_receivers
from reports.records import Table

__all__ = ["COLUMNS", "cost_study", "sweep_configs"]

COLUMNS = ("series", "label", "estimator", "iterations", "grid", "caustic_map",
           "splat_sigma", "time_s", "relmse", "pareto")


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
               reference_photons: int, quick: bool = False, progress=None,
               ) -> tuple[Table, EqualErrorSpeedup | None, tuple[float, float] | None]:
    """(table, equal-error speedup of the scene's own settings, that (time, error)).

    Parameters
    ----------
    reference, caustic
        Reference caustic irradiance of receiver 0 and its caustic region.
    reference_photons
        Photons per seed of the reference; the curve uses 1/256 .. 1/4 of it
        (1/64 .. 1/4 when ``quick``).
    """

    s = runner.settings
    rows = []
    base_frame, base_time = runner.timed(clock=caustic_seconds)
    base_error = score_value("relmse", base_frame.result.receivers[0].irradiance, reference,
                             mask=caustic, exposure=None)
    rows.append(_row("caustics_mapping", "scene settings", estimator=s.estimator,
                     iterations=s.iterations, grid=s.grid, caustic_map=s.caustic_map,
                     splat_sigma=s.splat_sigma, time_s=base_time, relmse=base_error))
    for config in sweep_configs(quick=quick, splat=s.splat):
        frame, seconds = runner.timed(clock=caustic_seconds, **config)
        error = score_value("relmse", frame.result.receivers[0].irradiance, reference,
                            mask=caustic, exposure=None)
        merged = {"estimator": s.estimator, "iterations": s.iterations, "grid": s.grid,
                  "caustic_map": s.caustic_map, "splat_sigma": s.splat_sigma, **config}
        rows.append(_row("caustics_mapping", _label(config), **merged, time_s=seconds,
                         relmse=error))
        if progress is not None:
            progress()
    fractions = _fractions(quick)
    ref_times, ref_errors = [], []
    # Timed as the method is (RealtimeRunner.timed): one untimed warm-up (kernel
    # compilation is no more a reference cost than shader compilation is a frame
    # cost), then the median of `repeats` runs (same seed, same estimate).
    estimate_receivers(runner.scene, photons=1, seeds=1, target_noise=1e-12)
    for fraction in fractions:
        photons = max(1, reference_photons // fraction)
        runs = [estimate_receivers(runner.scene, photons=photons, seeds=1,
                                   seed=s.seed + 10_000 + fraction, target_noise=1e-12)
                for _ in range(runner.repeats)]
        estimate = runs[-1]
        seconds = statistics.median(run.history[-1][2] for run in runs)
        error = score_value("relmse", estimate.caustic[0].irradiance, reference,
                            mask=caustic, exposure=None)
        rows.append(_row("reference", f"photons={photons}", estimator="", iterations=0, grid=0,
                         caustic_map=0, splat_sigma=0.0, time_s=seconds, relmse=error))
        ref_times.append(seconds)
        ref_errors.append(error)
        if progress is not None:
            progress()
    # The caustics-mapping rows come first, so front indices are row indices.
    realtime = [r for r in rows if r["series"] == "caustics_mapping"]
    front = set(pareto_front([r["time_s"] for r in realtime],
                             [r["relmse"] for r in realtime]).tolist())
    table = Table.from_records(COLUMNS, [{**row, "pareto": i in front}
                                         for i, row in enumerate(rows)])
    speedup = None
    if base_time > 0 and base_error > 0 and all(e > 0 for e in ref_errors):
        speedup = equal_error_speedup(base_time, base_error, ref_times, ref_errors)
    return table, speedup, (base_time, base_error)
