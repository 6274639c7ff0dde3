"""Mitsuba 3 ground truth for the caustics harness (docs/reference.md).

No module here imports Mitsuba or Dr.Jit at import time; :func:`._mi.load` does it,
once, on first use, after :func:`renderers.mitsuba.llvm.configure_drjit` has set
``DRJIT_LIBLLVM_PATH`` (or raised, naming ``caustics setup``: nothing here installs a
system package).

Public entry points
-------------------
``render_reference(scene, *, cache_dir=None, use_cache=True, progress=True)``
    -> :class:`renderers.results.RenderResult` (cached, K seeds, noise-targeted).
``trace_receiver_maps(scene, *, photons, seed, ...)``
    -> one seed of the event-filtered photon tracer.
``render_traced_camera(scene, *, photons, ...)``
    -> the camera tracer's K-seed image (sees through glass and water; the default
    reference camera).
``render_camera(scene, *, spp, seed, ...)``
    -> one seed of the ptracer camera image (``--camera ptracer``).
``load_mitsuba()``
    -> ``(mitsuba, drjit, variant)``, imported and configured once per process.
``mitsuba_versions()``
    -> the Mitsuba and Dr.Jit versions and the variant (cache keys, provenance).
"""

from __future__ import annotations

from renderers.mitsuba._mi import load as load_mitsuba
from renderers.mitsuba._mi import versions as mitsuba_versions
from renderers.mitsuba.camera import render_camera
from renderers.mitsuba.camera_trace import render_traced_camera
from renderers.mitsuba.photons import event_chains_counted, trace_receiver_maps
from renderers.mitsuba.reference import render_reference

__all__ = ["event_chains_counted", "load_mitsuba", "mitsuba_versions", "render_camera",
           "render_reference", "render_traced_camera", "trace_receiver_maps"]
