"""Render one scene with the caustics-mapping renderer under many settings.

One GL context and one geometry build serve every configuration of a study, and a
warm-up frame compiles the shaders before anything is timed. Frame time is the sum
of the per-pass times the renderer reports (on llvmpipe: ``ctx.finish()`` around
each pass and ``time.perf_counter``; the renderer's ``timer`` field says which).
"""

from __future__ import annotations

import statistics
from typing import Any

from harness.geometry import build_geometry
from harness.scene import Scene, with_settings

__all__ = ["RealtimeRunner", "frame_seconds"]


def frame_seconds(timings: dict[str, float]) -> float:
    """Seconds of one frame: the sum of its passes."""
    return float(sum(timings.values()))


class RealtimeRunner:
    """Caustics-mapping renders of ``scene`` with settings overrides.

    Use as a context manager so the GL context is released.
    """

    def __init__(self, scene: Scene, *, repeats: int = 3):
        from renderers.caustics_mapping.context import create_context  # noqa: PLC0415

        self.scene = scene
        self.geometry = build_geometry(scene)
        self.repeats = repeats
        self.ctx = create_context()
        self._warm = False

    def __enter__(self) -> RealtimeRunner:
        return self

    def __exit__(self, *exc) -> None:
        self.ctx.release()

    def render(self, **overrides: Any):
        """One frame (``renderers.caustics_mapping.renderer.Frame``) with overrides."""
        from renderers.caustics_mapping.renderer import render_frame  # noqa: PLC0415

        scene = with_settings(self.scene, overrides) if overrides else self.scene
        return render_frame(scene, ctx=self.ctx, geometry=self.geometry)

    def timed(self, **overrides: Any):
        """(frame, seconds): the median frame time over ``repeats`` renders, after a
        warm-up render on first use (shader compilation is not a frame cost)."""
        if not self._warm:
            self.render(**overrides)
            self._warm = True
        frames = [self.render(**overrides) for _ in range(self.repeats)]
        seconds = statistics.median(frame_seconds(f.result.timings) for f in frames)
        return frames[-1], seconds
