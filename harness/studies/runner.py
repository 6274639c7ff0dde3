"""Render one scene with the caustics-mapping renderer under many settings.

One GL context and one geometry build serve every configuration of a study, and a
warm-up frame compiles the shaders before anything is timed. Frame time is the sum
of the per-pass times the renderer reports (on llvmpipe: ``ctx.finish()`` around
each pass and ``time.perf_counter``; the renderer's ``timer`` field says which).
"""

from __future__ import annotations

import statistics
from typing import Any

from renderers.caustics_mapping.context import create_context
from renderers.caustics_mapping.presets import resolve_settings
from renderers.caustics_mapping.renderer import render_frame
from scenes import Scene, with_settings
from scenes.geometry import build_geometry

__all__ = ["CAMERA_PASSES", "RealtimeRunner", "caustic_seconds", "frame_seconds"]

#: Passes that only serve the camera image, not the receiver irradiance maps.
CAMERA_PASSES = ("camera", "shadow_map")


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

    def __init__(self, scene: Scene, *, repeats: int = 3):

        self.scene = scene
        self.geometry = build_geometry(scene)
        self.repeats = repeats
        self.ctx = create_context()
        self._warm = False

    @property
    def settings(self):
        """The scene's settings with the preset's choices filled in (what renders;
        ``scene.settings`` keeps them unset, so an override of ``grid`` still moves
        the grid-relative ones)."""
        return resolve_settings(self.scene.settings)

    def __enter__(self) -> RealtimeRunner:
        return self

    def __exit__(self, *exc) -> None:
        self.ctx.release()

    def render(self, **overrides: Any):
        """One frame (``renderers.caustics_mapping.renderer.Frame``) with overrides."""

        scene = with_settings(self.scene, overrides) if overrides else self.scene
        return render_frame(scene, ctx=self.ctx, geometry=self.geometry)

    def timed(self, *, clock=frame_seconds, **overrides: Any):
        """(frame, seconds): the median of ``clock(timings)`` over ``repeats``
        renders, after a warm-up render on first use (shader compilation is not a
        frame cost). ``clock`` is :func:`frame_seconds` or :func:`caustic_seconds`."""
        if not self._warm:
            self.render(**overrides)
            self._warm = True
        frames = [self.render(**overrides) for _ in range(self.repeats)]
        seconds = statistics.median(clock(f.result.timings) for f in frames)
        return frames[-1], seconds
