"""One row of a sweep as two Dask tasks: the method's timed render, then its scores.

:func:`render_row` times a (scene, method, setting) with the one timing function
``caustics compare`` uses (:func:`harness.compare.timed.timed_render`; a
caustics-mapping preset through this worker's GL context). :func:`score_row` runs the
rest of the comparison pipeline (:func:`harness.compare.pipeline.run_comparison`, the
``metrics`` stage: the same views, regions, metrics, stability checks, flux budgets
and provenance) on that render and the two references, and returns the
:class:`~reports.records.SceneComparison` its page is built from. The two are apart
so that renders run while the references are still being traced.
"""

from __future__ import annotations

import os
from dataclasses import dataclass

from harness.compare.pipeline import CompareOptions, run_comparison
from harness.compare.scoring import References
from harness.compare.timed import TimedRender, gl_runner, timed_render
from harness.sweep.worker import gl_context, worker_name
from renderers.methods import load_method
from renderers.results import RenderResult
from reports.records import SceneComparison
from scenes import Scene

__all__ = ["KEY_VALUES", "RowRender", "render_row", "row_values", "score_row"]

#: The values of a results.csv row, as (column, view, region, metric).
KEY_VALUES = (("relmse", "receiver0", "caustic", "relmse"),
              ("ssim", "receiver0", "caustic", "ssim"),
              ("flip", "receiver0", "caustic", "flip"),
              ("flux_ratio", "receiver0", "full", "flux_ratio"))

#: A sweep row is scored by the pipeline's scoring stage alone.
ROW_OPTIONS = CompareOptions(studies=("metrics",), progress=False)


@dataclass(frozen=True, eq=False)
class RowRender:
    """A method's timed render of one row, and the Dask worker that made it.

    Attributes
    ----------
    timed : TimedRender
        The render and its warm time (the timer says which clock and scope).
    worker : str
        The Dask worker that rendered it.
    """

    timed: TimedRender
    worker: str


def render_row(scene: Scene, method_name: str, *, repeats: int) -> RowRender:
    """Render ``scene`` (already configured by the method) once untimed, then
    ``repeats`` times, timed, as the comparison pipeline does (a method with a GL
    runner in this worker's GL context, made once per process); a Dask task (see the
    module docstring)."""
    method = load_method(method_name)
    with gl_runner(method, scene, repeats=repeats, context=gl_context) as runner:
        timed = timed_render(method, scene, repeats=repeats, runner=runner)
    # A local cluster shares the cores out (harness.sweep.worker): say so.
    share = os.environ.get("LP_NUM_THREADS")
    if share and runner is not None:
        timed = TimedRender(timed.result, timed.warm_seconds,
                            f"{timed.timer}; llvmpipe threads {share}", timed.hits,
                            timed.maps_seconds, timed.gl_renderer)
    return RowRender(timed, worker_name())


def score_row(scene: Scene, method_name: str, render: RowRender, reference: RenderResult,
              independent: RenderResult, *, extra: dict | None = None) -> SceneComparison:
    """Compare ``render`` with ``reference`` (noise floor: ``independent``) through the
    comparison pipeline; ``extra`` is recorded as the provenance's ``sweep`` (with the
    worker). A Dask task. A reference with no caustic light on any receiver gives a
    comparison with the status ``no caustic`` (as in ``caustics compare``): the
    client fails its row."""
    return run_comparison(scene, load_method(method_name), options=ROW_OPTIONS,
                          references=References(reference, independent), render=render.timed,
                          sweep={**(extra or {}), "worker": render.worker})


def row_values(comparison: SceneComparison) -> dict[str, float]:
    """The results.csv values of a comparison (:data:`KEY_VALUES`; NaN where a
    metric was not computed, e.g. an empty caustic region): for each, the excess
    (``excess_<column>``) and its 95 % interval (``excess_<column>_low``, ``_high``)
    first, the raw value (``<column>``) after, and the relMSE's noise floor (a
    diagnostic)."""
    values = {}
    nan = float("nan")
    for column, view, region, metric in KEY_VALUES:
        try:
            record = comparison.metric(view, region, metric)
        except KeyError:
            record = None
        low, high = (record.excess_ci95 if record is not None and record.excess_ci95
                     else (nan, nan))
        excess = record.excess if record is not None and record.excess is not None else nan
        values[f"excess_{column}"] = float(excess)
        values[f"excess_{column}_low"] = float(low)
        values[f"excess_{column}_high"] = float(high)
        values[column] = float(record.value) if record is not None else nan
    try:
        floor = comparison.metric("receiver0", "caustic", "relmse").noise_floor
    except KeyError:
        floor = None
    values["relmse_noise_floor"] = float("nan") if floor is None else float(floor)
    return values
