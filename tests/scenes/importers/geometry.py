"""How far apart two scenes' triangles are, for the round-trip tests."""

from __future__ import annotations

import numpy as np
from scipy.spatial import cKDTree

from scenes.geometry import build_geometry

__all__ = ["largest_vertex_gap"]


def largest_vertex_gap(ours, theirs) -> float:
    """The largest distance from a vertex of either scene's receivers and objects to the
    nearest vertex of the other's same part (a Hausdorff distance on vertices), over the
    part's bounding-box diagonal; the parts must pair up one to one."""
    a, b = build_geometry(ours), build_geometry(theirs)
    worst = 0.0
    for x, y in zip((*a.receivers, *a.objects), (*b.receivers, *b.objects), strict=True):
        px = np.asarray(x.mesh.positions, np.float64)
        py = np.asarray(y.mesh.positions, np.float64)
        size = float(np.linalg.norm(np.ptp(py, axis=0)))
        gap = max(cKDTree(py).query(px)[0].max(), cKDTree(px).query(py)[0].max())
        worst = max(worst, gap / size)
    return worst
