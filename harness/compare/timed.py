"""The one timing function: a method's render, warm, as ``compare``, sweep rows and
third-party methods all time it.

Every method, the caustics-mapping presets included, is rendered through its
protocol's ``render`` (:class:`renderers.methods.Method`); :func:`render_method` is
that one road. Policy (both sides of every comparison are timed this way;
``docs/statistics.md``, "Timing"): one untimed warm-up render (shader compilation,
first-call set-up), then ``repeats`` timed renders; the warm time is their median.

* A method with a GL runner (:class:`renderers.methods.GLMethod`, the presets)
  renders in the runner's GL context (:func:`gl_runner`: one context and one
  geometry build for the render and the studies): the clock is the sum of the
  frame's per-pass times, each pass bracketed by ``ctx.finish()`` and
  ``time.perf_counter`` on llvmpipe (GL timer queries where they are valid).
* A method whose images were rendered elsewhere
  (:class:`renderers.methods.ExternalMethod`): read once and not timed; its time is
  NaN, and what its renderer reported is carried in its metadata, labelled as not
  measured by the harness.
* Any other method: the sum of the passes it reports (``RenderResult.timings``), or
  else ``time.perf_counter`` around its ``render`` call, which also holds whatever
  set-up the method repeats per call (the timer says so).
"""

from __future__ import annotations

import contextlib
import math
import statistics
import time
from collections.abc import Callable, Iterator
from dataclasses import dataclass, field
from typing import Any

from harness.studies.runner import RealtimeRunner, caustic_seconds, frame_seconds
from renderers.methods import Method, has_gl_runner, renders_elsewhere
from renderers.results import RenderResult
from scenes import Scene
from scenes.geometry import SceneGeometry

__all__ = ["TimedRender", "gl_runner", "render_method", "timed_render"]


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
        A method with a GL runner: its render's per-vertex records
        (``RenderResult.records``: grid and rim patches, each vertex's flux at the
        share its splats draw; for the stability checks and the flux budget). None
        for any other method, even one whose result carries records of a render it
        wraps (they would not describe its maps).
    maps_seconds : float or None
        Median time of the passes that make the receiver maps (s): the scope of the
        equal-error speedup (methods with a GL runner only).
    gl_renderer : str or None
        The OpenGL renderer (llvmpipe, an NVIDIA GPU), for methods with a GL runner.
    """

    result: RenderResult
    warm_seconds: float
    timer: str
    hits: dict | None = field(default=None, repr=False)  # large per-vertex arrays
    maps_seconds: float | None = None
    gl_renderer: str | None = None


@contextlib.contextmanager
def gl_runner(method: Method, scene: Scene, *, repeats: int, needed: bool = True,
              context: Callable[[], Any] | None = None) -> Iterator[RealtimeRunner | None]:
    """The GL runner of ``scene`` (as ``method.configure`` returned it), rendering
    ``repeats`` timed frames per configuration, when the method has one
    (:func:`renderers.methods.has_gl_runner`) and ``needed``; else None.
    ``context``: gives the GL context to render in and keep (a sweep worker's, made
    once per process); None: the runner makes and releases its own."""
    if not (needed and has_gl_runner(method)):
        yield None
        return
    ctx = context() if context is not None else None
    with RealtimeRunner(scene, repeats=repeats, ctx=ctx) as runner:
        yield runner


def render_method(method: Method, scene: Scene, *, ctx: Any = None,
                  geometry: SceneGeometry | None = None) -> RenderResult:
    """One render of ``scene`` by ``method``, through its protocol's ``render``: with
    ``ctx``, a method with a GL runner draws in that GL context on ``geometry``
    (:meth:`renderers.methods.GLMethod.in_context`).

    Raises
    ------
    ValueError
        ``ctx`` for a method without a GL runner.
    """
    if ctx is None:
        return method.render(scene)
    if not has_gl_runner(method):
        raise ValueError(f"method {method.name!r} has no GL runner: it renders in no "
                         "GL context of the caller's")
    return method.in_context(ctx, geometry=geometry).render(scene)


def timed_render(method: Method, scene: Scene, *, repeats: int,
                 runner: RealtimeRunner | None = None) -> TimedRender:
    """Render ``scene`` (as ``method.configure`` returned it) once untimed, then
    ``repeats`` times, timed (module docstring).

    Parameters
    ----------
    method : Method
        The method; one with a GL runner (:func:`renderers.methods.has_gl_runner`)
        needs ``runner``.
    scene : Scene
        The configured scene.
    repeats : int
        Timed renders (the median is kept), at least 1.
    runner : RealtimeRunner, optional
        The method's GL runner of ``scene`` (:func:`gl_runner`).

    Raises
    ------
    ValueError
        A method with a GL runner without one, or ``repeats < 1``.
    """
    if repeats < 1:
        raise ValueError(f"repeats must be >= 1, got {repeats}")
    if has_gl_runner(method):
        if runner is None:
            raise ValueError(f"method {method.name!r} has a GL runner: timed_render needs "
                             "it (harness.compare.timed.gl_runner)")
        result, seconds = runner.timed_method(lambda: render_method(
            method, scene, ctx=runner.ctx, geometry=runner.geometry))
        return TimedRender(result, seconds,
                           f"sum of the passes ({result.timer}), median of {repeats} "
                           "after a warm-up", result.records,
                           runner.median(clock=caustic_seconds),
                           runner.ctx.info.get("GL_RENDERER", "unknown"))
    if renders_elsewhere(method):
        # Reading files is not rendering: nothing here would time the renderer.
        return TimedRender(render_method(method, scene), math.nan,
                           "not measured by the harness (images rendered elsewhere)")
    render_method(method, scene)
    walls, sums, result = [], [], None
    for _ in range(repeats):
        start = time.perf_counter()
        result = render_method(method, scene)
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
