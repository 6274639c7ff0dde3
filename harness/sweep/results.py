"""``results.csv``: one row per (scene, method, setting), and the Pareto front per scene.

Columns, in order: ``scene``, ``method``, one column per setting the grid varies
(in the sweep file's order), then

* for each of ``relmse``, ``ssim``, ``flip`` (receiver 0, the scene's caustic
  region: thresholded on the independent reference, the same texels for every row
  of the scene, :func:`harness.compare.regions.scene_caustic_region`) and
  ``flux_ratio`` (receiver 0, whole map): first ``excess_<metric>``, the method's
  own error against the noise-free image (SSIM: the deficit below a perfect
  method's; FLIP: above it; flux: ratio − 1), then its 95 % interval
  ``excess_<metric>_low`` and ``_high``, then the raw value ``<metric>`` (the
  formulas are in ``reports.records.METRIC_FORMULAS``), as in ``caustics
  compare``'s summary and records;
* ``time_warm_ms``: the method's warm frame time (median after a warm-up; for the
  caustics-mapping presets the sum of the passes, ``ctx.finish()`` and
  ``time.perf_counter`` on llvmpipe);
* ``worker``: the Dask worker that rendered the row (kept from the run that
  computed it when the row is cached);
* ``cached``: ``true`` when the row was read from the results cache;
* ``error``, ``stage``: why and where a failed row failed (empty otherwise);
* ``pareto``: on its scene's Pareto front of (``time_warm_ms``, ``excess_relmse``):
  no other row of the scene is no slower and no less accurate, and better in one;
* ``relmse_noise_floor``: a diagnostic, the raw relMSE of the independent reference
  (other seeds) against the reference (it holds both references' noise, no
  yardstick); ``reference_noise``: the reference's relative noise in the caustic
  region;
* ``page``: the row's page folder; ``key``: its results-cache key.

A number that is not finite, or was not computed, is an empty cell.
"""

from __future__ import annotations

import csv
import io
import math
from pathlib import Path

import numpy as np

from harness.studies.pareto import pareto_front
from harness.sweep.run import RowResult
from scenes.files import atomic_write_bytes

__all__ = ["VALUE_COLUMNS", "pareto_keys", "results_columns", "write_results_csv"]

#: The metric columns, in order: per metric the excess, its interval, the raw value.
VALUE_COLUMNS = tuple(column for metric in ("relmse", "ssim", "flip", "flux_ratio")
                      for column in (f"excess_{metric}", f"excess_{metric}_low",
                                     f"excess_{metric}_high", metric))


def results_columns(grid: tuple[str, ...]) -> tuple[str, ...]:
    """The header of ``results.csv`` for a grid over ``grid``."""
    return ("scene", "method", *grid, *VALUE_COLUMNS, "time_warm_ms", "worker", "cached",
            "error", "stage", "pareto", "relmse_noise_floor", "reference_noise", "page", "key")


def pareto_keys(rows: list[RowResult]) -> set[str]:
    """Row keys on their scene's Pareto front of (time_warm_ms, excess_relmse); failed rows
    and rows without both numbers finite are never on it."""
    keys = set()
    scenes = dict.fromkeys(r.job.scene.name for r in rows)
    for scene in scenes:
        mine = [r for r in rows if r.job.scene.name == scene and not r.failed]
        times = np.array([_number(r.time_warm_ms) for r in mine], float)
        errors = np.array([_number(r.values.get("excess_relmse")) for r in mine], float)
        keys.update(mine[i].job.key for i in pareto_front(times, errors))
    return keys


def _number(value) -> float:
    return float("nan") if value is None else float(value)


def _cell(value) -> str:
    if value is None:
        return ""
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, float):
        return repr(value) if math.isfinite(value) else ""
    if isinstance(value, tuple):
        return "x".join(_cell(v) for v in value)
    return str(value)


def write_results_csv(path: str | Path, rows: list[RowResult], *,
                      grid: tuple[str, ...]) -> None:
    """Write ``results.csv`` (see the module docstring) atomically."""
    front = pareto_keys(rows)
    buffer = io.StringIO()
    writer = csv.writer(buffer, lineterminator="\n")
    writer.writerow(results_columns(grid))
    for row in rows:
        job, setting = row.job, dict(row.job.setting.items)
        writer.writerow([_cell(v) for v in (
            job.scene.name, job.method, *(setting[name] for name in grid),
            *(row.values.get(c) for c in VALUE_COLUMNS), row.time_warm_ms, row.worker,
            row.cached, row.error, row.stage, job.key in front,
            row.values.get("relmse_noise_floor"), row.details.get("reference_noise"),
            job.folder if row.page is not None else "", job.key)])
    atomic_write_bytes(path, buffer.getvalue().encode("utf-8"))
