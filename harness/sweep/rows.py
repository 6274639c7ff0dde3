"""One row of a sweep as two Dask tasks: the method's timed render, then its scores.

:func:`render_row` renders a (scene, method, setting) as ``caustics compare`` does:
a caustics-mapping preset through this worker's GL context (one warm-up frame,
then ``repeats`` frames; the warm time is the median of the sum of each frame's
per-pass times, on llvmpipe ``ctx.finish()`` and ``time.perf_counter``), any other
method through its ``render`` (median wall time of the call, after a warm-up).

:func:`score_row` compares that render with the reference and the independent
reference (the noise floor) exactly as ``compare --studies metrics`` does (the
same views, regions, metrics, stability checks, flux budget and provenance), and
returns the :class:`~reports.records.SceneComparison` its page is built from. The
two are apart so that renders run while the references are still being traced.
"""

from __future__ import annotations

import os
import statistics
import time
from dataclasses import asdict, dataclass

from harness.checks.stability import stability_summary
from harness.compare.budget import flux_budget
from harness.compare.isolation import NoCausticError

# The comparison's own view and scoring steps, so a sweep row scores exactly as
# `caustics compare` does (they are module-private there: one pipeline, two callers).
from harness.compare.pipeline import _reference_provenance, _score_views, _views
from harness.studies.runner import frame_seconds
from harness.sweep.worker import gl_context, worker_name
from renderers.methods import load_method
from renderers.results import RenderResult
from reports.records import SceneComparison
from scenes import Scene, effects_of
from scenes.geometry import build_geometry

__all__ = ["KEY_VALUES", "MethodRender", "render_row", "row_values", "score_row"]

#: The values of a results.csv row, as (column, view, region, metric).
KEY_VALUES = (("relmse", "receiver0", "caustic", "relmse"),
              ("ssim", "receiver0", "caustic", "ssim"),
              ("flip", "receiver0", "caustic", "flip"),
              ("flux_ratio", "receiver0", "full", "flux_ratio"))


@dataclass(frozen=True, eq=False)
class MethodRender:
    """A method's render of one row, timed.

    Attributes
    ----------
    result : RenderResult
        The last timed render.
    warm_seconds : float
        Median over ``repeats`` renders after a warm-up (see the module docstring).
    timer : str
        What ``warm_seconds`` measured, with which clock.
    hits : dict of ndarray or None
        The caustics-mapping per-vertex records (for the stability checks).
    worker : str
        The Dask worker that rendered it.
    gl_renderer : str or None
        The OpenGL renderer (llvmpipe, an NVIDIA GPU), for caustics mapping.
    """

    result: RenderResult
    warm_seconds: float
    timer: str
    hits: dict | None
    worker: str
    gl_renderer: str | None = None


def render_row(scene: Scene, method_name: str, *, repeats: int) -> MethodRender:
    """Render ``scene`` (already configured by the method) ``1 + repeats`` times with
    ``method_name``; a Dask task (see the module docstring)."""
    method = load_method(method_name)
    if method.studies:
        # Deferred: moderngl and the GL passes load only where a method renders.
        from renderers.caustics_mapping.renderer import render_frame  # noqa: PLC0415

        ctx = gl_context()
        geometry = build_geometry(scene)
        render_frame(scene, ctx=ctx, geometry=geometry, lookups=False)  # compiles shaders
        frames = [render_frame(scene, ctx=ctx, geometry=geometry, lookups=False)
                  for _ in range(repeats)]
        seconds = statistics.median(frame_seconds(f.result.timings) for f in frames)
        result = frames[-1].result
        # A local cluster shares the cores out (harness.sweep.worker): say so.
        share = os.environ.get("LP_NUM_THREADS")
        threads = f"; llvmpipe threads {share}" if share else ""
        return MethodRender(result, seconds, f"sum of the passes ({result.timer}), median of "
                            f"{repeats} after a warm-up{threads}", frames[-1].hits,
                            worker_name(), ctx.info.get("GL_RENDERER", "unknown"))
    method.render(scene)
    walls, result = [], None
    for _ in range(repeats):
        start = time.perf_counter()
        result = method.render(scene)
        walls.append(time.perf_counter() - start)
    return MethodRender(result, statistics.median(walls), "time.perf_counter around render() "
                        f"(whole call), median of {repeats} after a warm-up", None,
                        worker_name())


def _provenance(scene: Scene, method_name: str, render: MethodRender, *,
                reference: RenderResult, independent: RenderResult, extra: dict) -> dict:
    result = render.result
    timings = {k: v * 1e3 for k, v in result.timings.items()}
    if render.hits is not None:
        method = {"caustics_mapping": {
            "preset": result.metadata.get("preset"), "passes": result.metadata.get("passes"),
            "timings_ms": timings, "frame_time_ms": render.warm_seconds * 1e3,
            "timer": render.timer, "lost_splats": result.metadata.get("lost_splats"),
            "status_counts": result.metadata.get("status_counts"),
            "status_flux_fraction": result.metadata.get("status_flux_fraction"),
            "gl_renderer": render.gl_renderer}}
    else:
        method = {"method": {"name": method_name, "renderer": result.renderer,
                             "timings_ms": timings, "frame_time_ms": render.warm_seconds * 1e3,
                             "timer": render.timer, "metadata": result.metadata}}
    return {"scene_file": scene.source, **method,
            **_reference_provenance(reference, independent),
            "sweep": {**extra, "worker": render.worker}}


def score_row(scene: Scene, method_name: str, render: MethodRender, reference: RenderResult,
              independent: RenderResult, *, extra: dict | None = None) -> SceneComparison:
    """Compare ``render`` with ``reference`` (noise floor: ``independent``): every
    metric per view and region, stability, flux budget, provenance (``extra`` is
    added under ``provenance["sweep"]``). A Dask task.

    Raises
    ------
    NoCausticError
        The reference puts no caustic light on any receiver: nothing to compare (as
        in ``caustics compare``).
    """
    method = load_method(method_name)
    if sum(float(r.total_flux().sum()) for r in reference.receivers) == 0.0:
        raise NoCausticError("no caustic: the reference puts no caustic light on any "
                             "receiver (check where the light, objects and receivers are)")
    result = render.result
    geometry = build_geometry(scene)
    views, camera_note = _views(scene, geometry, result, reference, independent)
    metrics, images, exposure, files = _score_views(views)
    stability = stability_summary(scene, geometry, result, None, hits=render.hits)
    budget = flux_budget(result.metadata, stability, result.receivers, reference.receivers)
    provenance = _provenance(scene, method_name, render, reference=reference,
                             independent=independent, extra=extra or {})
    if camera_note:
        provenance["camera_note"] = camera_note
    return SceneComparison(
        name=scene.name, description=scene.info.description, source=scene.source,
        effects=effects_of(scene), settings=asdict(scene.settings), metrics=tuple(metrics),
        images=images, exposure=exposure, provenance=provenance, files=files,
        stability=stability, method=method.name, method_description=method.description,
        flux_budget=budget)


def row_values(comparison: SceneComparison) -> dict[str, float]:
    """The results.csv values of a comparison (:data:`KEY_VALUES`; NaN where a
    metric was not computed, e.g. an empty caustic region), and the relMSE's noise
    floor."""
    values = {}
    for column, view, region, metric in KEY_VALUES:
        try:
            values[column] = float(comparison.metric(view, region, metric).value)
        except KeyError:
            values[column] = float("nan")
    try:
        floor = comparison.metric("receiver0", "caustic", "relmse").noise_floor
    except KeyError:
        floor = None
    values["relmse_noise_floor"] = float("nan") if floor is None else float(floor)
    return values
