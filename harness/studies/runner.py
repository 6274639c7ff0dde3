"""Render one scene with the caustics-mapping renderer under many settings.

One GL context and one geometry build serve every configuration of a study (their
time is the method's ``t_build``), and an untimed warm-up frame of each
configuration compiles its shaders before it is timed (the first one's excess over
its warm time is the method's ``t_compile``; :mod:`harness.studies.timing`). Frame
time is the sum of the per-pass times the renderer reports (on llvmpipe:
``ctx.finish()`` around each pass and ``time.perf_counter``; the renderer's
``timer`` field says which); the receiver-map pass includes the maps' read-back.

A frame draws the passes the method's own render draws (no caustic-map atlas that the
camera does not read), so that the method's render, which the comparison times in
the runner's context (:meth:`RealtimeRunner.timed_method`), is the runner's
configuration without overrides.
"""

from __future__ import annotations

import statistics
import time
from collections.abc import Callable
from typing import Any, TypeVar

from harness.studies.timing import OneOffCosts
from renderers.caustics_mapping.context import create_context
from renderers.caustics_mapping.presets import resolve_scene
from renderers.caustics_mapping.renderer import render_frame
from renderers.results import RenderResult
from scenes import Scene, with_settings
from scenes.geometry import build_geometry

__all__ = ["CAMERA_PASSES", "RealtimeRunner", "caustic_seconds", "frame_seconds"]

_T = TypeVar("_T")

#: Passes that only serve the camera image, not the receiver irradiance maps.
CAMERA_PASSES = ("camera", "camera_backfaces", "shadow_map")


def frame_seconds(timings: dict[str, float]) -> float:
    """Seconds of one frame: the sum of its passes."""
    return float(sum(timings.values()))


def caustic_seconds(timings: dict[str, float]) -> float:
    """Seconds of the passes that produce the receiver irradiance maps (everything
    but :data:`CAMERA_PASSES`): the like-for-like cost against the photon tracer,
    which produces only those maps."""
    return float(sum(v for k, v in timings.items() if k not in CAMERA_PASSES))


class RealtimeRunner:
    """Caustics-mapping renders of ``scene`` with settings overrides.

    Use as a context manager so the GL context is released.
    """

    def __init__(self, scene: Scene, *, repeats: int = 3, ctx=None):
        # Driver start-up (the EGL display, the device choice) is excluded as the
        # Dr.Jit backend's is on the reference side (it happens at import): only
        # the first context in a process pays it, so timing it would make the
        # first runner's build time differ from every later one's. A context handed
        # in (a sweep worker's, made once per process) is kept, not released.
        self._own = ctx is None
        if self._own:
            create_context().release()
        start = time.perf_counter()
        self.scene = scene
        self.geometry = build_geometry(scene)
        self.repeats = repeats
        self.ctx = create_context() if self._own else ctx
        #: The one-off set-up (s): the scene's meshes and the GL context.
        self.build_s = time.perf_counter() - start
        self._first: dict[tuple, dict[str, float]] = {}
        self._timed: dict[tuple, list[dict[str, float]]] = {}

    @property
    def settings(self):
        """The scene's settings with the preset's choices filled in (what renders;
        ``scene.settings`` keeps them unset, so an override of ``grid`` still moves
        the grid-relative ones)."""
        return resolve_scene(self.scene, self.geometry).settings

    def __enter__(self) -> RealtimeRunner:
        return self

    def __exit__(self, *exc) -> None:
        if self._own:
            self.ctx.release()

    def render(self, **overrides: Any):
        """One frame (``renderers.caustics_mapping.renderer.Frame``) with overrides:
        the passes the method's render draws, no positions atlases read back."""

        scene = with_settings(self.scene, overrides) if overrides else self.scene
        return render_frame(scene, ctx=self.ctx, geometry=self.geometry, lookups=False,
                            atlas=False)

    def timed(self, *, clock=frame_seconds, **overrides: Any):
        """(frame, seconds): the median of ``clock(timings)`` over ``repeats``
        renders, after an untimed warm-up render on first use of these overrides
        (shader compilation is not a frame cost). ``clock`` is
        :func:`frame_seconds` or :func:`caustic_seconds`."""
        return self._time(tuple(sorted(overrides.items())),
                           lambda: self.render(**overrides), lambda f: f.result.timings,
                           clock)

    def timed_method(self, render: Callable[[], RenderResult], *,
                     clock=frame_seconds) -> tuple[RenderResult, float]:
        """(result, seconds): ``render``, a method's own render of :attr:`scene` in
        :attr:`ctx`, timed as :meth:`timed` times a configuration. It is booked as the
        configuration without overrides (the same passes on the same scene): a study's
        :meth:`timed` of it needs no second warm-up, and :meth:`one_off` reads its
        first render."""
        return self._time((), render, lambda r: r.timings, clock)

    def _time(self, key: tuple, render: Callable[[], _T],
               timings: Callable[[_T], dict[str, float]], clock) -> tuple[_T, float]:
        if key not in self._first:
            self._first[key] = timings(render())
        outputs = [render() for _ in range(self.repeats)]
        self._timed[key] = [timings(o) for o in outputs]
        seconds = statistics.median(clock(t) for t in self._timed[key])
        return outputs[-1], seconds

    def median(self, *, clock=frame_seconds, **overrides: Any) -> float:
        """The median of ``clock(timings)`` over the renders :meth:`timed` last
        took of these overrides (another scope of the same frames)."""
        key = tuple(sorted(overrides.items()))
        return statistics.median(clock(t) for t in self._timed[key])

    def one_off(self, *, clock=caustic_seconds) -> OneOffCosts:
        """The method's one-off costs: ``build_s``, and the first frame's excess
        over the warm time of the same configuration (the first one rendered), both
        under ``clock``'s scope."""
        if not self._first:
            raise RuntimeError("one_off() needs a timed() configuration first")
        key = next(iter(self._first))
        first = clock(self._first[key])
        warm = statistics.median(clock(t) for t in self._timed[key])
        return OneOffCosts(build_s=self.build_s, compile_s=max(first - warm, 0.0))
