"""Mitsuba 3 ground truth for the caustics harness (DESIGN.md, "Mitsuba reference").

No module here imports Mitsuba or Dr.Jit at import time; :func:`._mi.load` does it,
once, on first use, after :func:`renderers.mitsuba.llvm.configure_drjit` has set
``DRJIT_LIBLLVM_PATH``.

Public entry points
-------------------
``render_reference(scene, *, cache_dir=None, use_cache=True, progress=True)``
    -> :class:`renderers.results.RenderResult` (cached, K seeds, noise-targeted).
``trace_receiver_maps(scene, *, photons, seed, ...)``
    -> one seed of the event-filtered photon tracer.
``render_camera(scene, *, spp, seed, ...)``
    -> one seed of the ptracer camera image.
"""

from __future__ import annotations

from renderers.mitsuba.camera import render_camera
from renderers.mitsuba.photons import event_chains_counted, trace_receiver_maps
from renderers.mitsuba.reference import render_reference

__all__ = ["event_chains_counted", "render_camera", "render_reference", "trace_receiver_maps"]
