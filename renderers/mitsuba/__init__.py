"""Mitsuba 3 ground truth for the caustics harness (DESIGN.md, "Mitsuba reference").

Nothing here imports Mitsuba or Dr.Jit at module import time; :mod:`._mi` does it,
once, after :func:`harness.system.configure_drjit` has set ``DRJIT_LIBLLVM_PATH``.

Public entry points
-------------------
``render_reference(scene, *, cache_dir=None, use_cache=True, progress=True)``
    -> :class:`harness.results.RenderResult` (cached, K seeds, noise-targeted).
``trace_receiver_maps(scene, *, photons, seed, ...)``
    -> one seed of the event-filtered photon tracer.
``render_camera(scene, *, spp, seed, ...)``
    -> one seed of the ptracer camera image.
"""

from __future__ import annotations

__all__ = ["event_chains_counted", "render_camera", "render_reference", "trace_receiver_maps"]


def __getattr__(name: str):
    # Lazy: importing the package must not import Mitsuba (the CLI lists commands
    # without paying for the JIT).
    if name == "render_reference":
        from renderers.mitsuba.reference import render_reference  # noqa: PLC0415

        return render_reference
    if name in ("trace_receiver_maps", "event_chains_counted"):
        from renderers.mitsuba import photons  # noqa: PLC0415

        return getattr(photons, name)
    if name == "render_camera":
        from renderers.mitsuba.camera import render_camera  # noqa: PLC0415

        return render_camera
    raise AttributeError(name)
