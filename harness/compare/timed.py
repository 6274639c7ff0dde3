"""The one timing function: a method's render, warm, as ``compare``, sweep rows and
third-party methods all time it.

Policy (both sides of every comparison are timed this way; ``docs/statistics.md``,
"Timing"): one untimed warm-up render (shader compilation, first-call set-up), then
``repeats`` timed renders; the warm time is their median.

* A caustics-mapping preset renders through a :class:`~harness.studies.runner.RealtimeRunner`
  (one GL context and one geometry build for every configuration): the clock is the
  sum of the frame's per-pass times, each pass bracketed by ``ctx.finish()`` and
  ``time.perf_counter`` on llvmpipe (GL timer queries where they are valid).
* Any other method: ``time.perf_counter`` around its ``render`` call, which also holds
  whatever set-up the method repeats per call (the timer says so).
"""

from __future__ import annotations

import statistics
import time
from dataclasses import dataclass, field

from harness.studies.runner import RealtimeRunner, caustic_seconds, frame_seconds
from renderers.methods import Method
from renderers.results import RenderResult
from scenes import Scene

__all__ = ["TimedRender", "timed_render"]


@dataclass(frozen=True, eq=False)
class TimedRender:
    """A method's render of one scene, timed.

    Attributes
    ----------
    result : RenderResult
        The last timed render.
    warm_seconds : float
        Median over the timed renders after the warm-up (s).
    timer : str
        What ``warm_seconds`` measured, with which clock.
    hits : dict of ndarray or None
        The caustics-mapping per-vertex records, grid and rim patches, each vertex's
        flux at the share its splats draw (``Frame.traced_records``; for the
        stability checks and the flux budget).
    maps_seconds : float or None
        Median time of the passes that make the receiver maps (s): the scope of the
        equal-error speedup (caustics mapping only).
    gl_renderer : str or None
        The OpenGL renderer (llvmpipe, an NVIDIA GPU), for caustics mapping.
    """

    result: RenderResult
    warm_seconds: float
    timer: str
    hits: dict | None = field(default=None, repr=False)  # large per-vertex arrays
    maps_seconds: float | None = None
    gl_renderer: str | None = None


def timed_render(method: Method, scene: Scene, *, repeats: int,
                 runner: RealtimeRunner | None = None) -> TimedRender:
    """Render ``scene`` (as ``method.configure`` returned it) once untimed, then
    ``repeats`` times, timed (module docstring).

    Parameters
    ----------
    method : Method
        The method; a caustics-mapping preset (``method.studies``) needs ``runner``.
    scene : Scene
        The configured scene.
    repeats : int
        Timed renders (the median is kept), at least 1.
    runner : RealtimeRunner, optional
        The caustics-mapping runner of ``scene`` (its GL context and geometry).

    Raises
    ------
    ValueError
        A caustics-mapping method without a runner, or ``repeats < 1``.
    """
    if repeats < 1:
        raise ValueError(f"repeats must be >= 1, got {repeats}")
    if method.studies:
        if runner is None:
            raise ValueError(f"method {method.name!r} renders with caustics mapping: "
                             "timed_render needs its RealtimeRunner")
        frame, seconds = runner.timed()
        return TimedRender(frame.result, seconds,
                           f"sum of the passes ({frame.result.timer}), median of {repeats} "
                           "after a warm-up", frame.traced_records(),
                           runner.median(clock=caustic_seconds),
                           runner.ctx.info.get("GL_RENDERER", "unknown"))
    method.render(scene)
    walls, sums, result = [], [], None
    for _ in range(repeats):
        start = time.perf_counter()
        result = method.render(scene)
        walls.append(time.perf_counter() - start)
        sums.append(frame_seconds(result.timings))
    if result.timings:
        # The method reports its passes: the same scope as the presets' frame time.
        return TimedRender(result, statistics.median(sums),
                           f"sum of the method's passes ({result.timer}), median of "
                           f"{repeats} after a warm-up")
    return TimedRender(result, statistics.median(walls),
                       f"time.perf_counter around render() (whole call), median of {repeats} "
                       "after a warm-up")
