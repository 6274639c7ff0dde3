"""The grid's footprint on the receivers: the default width of `points` splats.

With ``splat = "points"`` and no ``splat_sigma`` (outside the paper preset), every
splat's standard deviation is one mean spacing of neighbouring hits, measured on
this frame's trace records: for each pair of grid neighbours (along x or y in one
object view) that both hit the same receiver, the distance between the hits in
caustic-map texels at the pair's midpoint. One σ of one mean spacing makes
neighbouring splats overlap into a continuous caustic where the grid is spread, and
stays a few texels wide at a focus.
"""

from __future__ import annotations

import numpy as np

from renderers.caustics_mapping.caustic_trace import STATUS, Trace
from renderers.caustics_mapping.lights import LightSetup

__all__ = ["mean_hit_spacing_texels"]

#: Width used when no two neighbours hit the same receiver (caustic-map texels).
FALLBACK_TEXELS = 1.0


def mean_hit_spacing_texels(traces: list[Trace], light: LightSetup, *, grid: int,
                            caustic_size: int) -> float:
    """Mean spacing (caustic-map texels) of neighbouring hits over ``traces``.

    The records are read back from the GPU (one synchronisation, counted in the
    splat pass that calls this).
    """
    view = light.map_views[0]
    x0, x1, y0, y1 = view.bounds
    texel_plane = max(x1 - x0, y1 - y0) / caustic_size      # tangent or m per texel
    total, count = 0.0, 0
    for trace in traces:
        rec = np.frombuffer(trace.records.read(), np.float32).reshape(-1, grid, grid, 5, 4)
        hit = rec[..., 2, :3].astype(np.float64)
        ok = np.rint(rec[..., 2, 3]) == STATUS["hit"]
        receiver = np.rint(rec[..., 3, 3])
        for axis in (1, 2):
            a = [slice(None)] * 3
            b = [slice(None)] * 3
            a[axis], b[axis] = slice(None, -1), slice(1, None)
            pair = ok[tuple(a)] & ok[tuple(b)] & (receiver[tuple(a)] == receiver[tuple(b)])
            if not pair.any():
                continue
            pa, pb = hit[tuple(a)][pair], hit[tuple(b)][pair]
            if view.perspective:
                mid = 0.5 * (pa + pb)
                width = texel_plane * np.linalg.norm(mid - light.position, axis=1)
            else:
                width = np.full(len(pa), texel_plane)
            total += float(np.sum(np.linalg.norm(pa - pb, axis=1) / width))
            count += len(pa)
    return total / count if count else FALLBACK_TEXELS
