"""Caustics mapping (Shah, Konttinen, Pattanaik, IEEE TVCG 2007) on OpenGL via moderngl.

Passes, one module each with its GLSL beside it: :mod:`.receiver_positions`,
:mod:`.object_positions`, :mod:`.caustic_trace`, :mod:`.caustic_splat`,
:mod:`.receiver_splat` (both splat passes share ``splat_kernels.glsl``: points,
footprint and triangle kernels), :mod:`.lowpass`, :mod:`.shadow_map`, :mod:`.camera`;
:mod:`.light_sample` orders them for one light sample, :mod:`.splat_maps` the splat
passes and the caustic map the camera reads.
:mod:`.estimators` is the NumPy mirror of the intersection estimators;
:mod:`.presets` the ``paper`` and ``strong`` presets and :mod:`.methods` the same as
registered methods (:mod:`renderers.methods`).
"""

from renderers.caustics_mapping.context import GLError, create_context
from renderers.caustics_mapping.estimators import MapLookup, MirrorResult, estimate_distances
from renderers.caustics_mapping.renderer import Frame, newton_eps, render, render_frame

__all__ = [
    "Frame",
    "GLError",
    "MapLookup",
    "MirrorResult",
    "create_context",
    "estimate_distances",
    "newton_eps",
    "render",
    "render_frame",
]
