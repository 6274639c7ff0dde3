"""Exact ray casting against the scene's own triangles (Mitsuba's ray tracer).

The convergence tables compare each estimator's hit distance with the exact distance
along the same ray (v, r) to the receivers; this module provides that exact distance
from the very triangles both renderers were given (``harness.geometry``).
"""

from __future__ import annotations

import functools

import numpy as np

from harness.geometry import SceneGeometry, TriangleMesh
from harness.system import configure_drjit

__all__ = ["RayHits", "ReceiverTracer", "cast_rays"]

VARIANT = "llvm_ad_rgb"


@functools.lru_cache(maxsize=1)
def _mitsuba():
    configure_drjit()
    import mitsuba as mi  # noqa: PLC0415 - needs DRJIT_LIBLLVM_PATH set first

    if mi.variant() is None:
        mi.set_variant(VARIANT)
    return mi


def _mesh_scene(mi, mesh: TriangleMesh, name: str):
    """A one-shape Mitsuba scene holding exactly ``mesh``'s triangles."""
    shape = mi.Mesh(name, vertex_count=len(mesh.positions), face_count=len(mesh.faces),
                    has_vertex_normals=False, has_vertex_texcoords=False)
    params = mi.traverse(shape)
    params["vertex_positions"] = mesh.positions.astype(np.float32).ravel()
    params["faces"] = mesh.faces.astype(np.uint32).ravel()
    params.update()
    return mi.load_dict({"type": "scene", name: shape})


class RayHits:
    """Nearest receiver hits of a batch of rays.

    Attributes
    ----------
    distance : ndarray (N,), float64
        Distance along the unit direction to the nearest receiver, metres; ``inf``
        where no receiver is hit.
    receiver : ndarray (N,), int
        Index into ``scene.receivers`` of the receiver hit, −1 for none.
    position : ndarray (N, 3), float64
        Hit points, metres (NaN rows where there is no hit).
    """

    def __init__(self, distance, receiver, position):
        self.distance = distance
        self.receiver = receiver
        self.position = position


class ReceiverTracer:
    """Build once per geometry, then ``tracer(origins, directions) -> RayHits``."""

    def __init__(self, geometry: SceneGeometry):
        mi = _mitsuba()
        self._mi = mi
        self._scenes = [_mesh_scene(mi, rec.mesh, f"receiver{i}")
                        for i, rec in enumerate(geometry.receivers)]

    def __call__(self, origins, directions) -> RayHits:
        """Cast rays from ``origins`` (N, 3) along ``directions`` (N, 3), metres.

        Directions are normalised here, so distances are in metres.
        """
        mi = self._mi
        o = np.asarray(origins, np.float64)
        d = np.asarray(directions, np.float64)
        d = d / np.linalg.norm(d, axis=1, keepdims=True)
        ray = mi.Ray3f(mi.Point3f(o.T.astype(np.float32)), mi.Vector3f(d.T.astype(np.float32)))
        best = np.full(len(o), np.inf)
        index = np.full(len(o), -1)
        for i, scene in enumerate(self._scenes):
            si = scene.ray_intersect(ray)
            t = np.where(np.asarray(si.is_valid()), np.asarray(si.t, np.float64), np.inf)
            closer = t < best
            best[closer], index[closer] = t[closer], i
        hit = np.isfinite(best)
        position = np.where(hit[:, None], o + np.where(hit, best, 0.0)[:, None] * d, np.nan)
        return RayHits(best, index, position)


def cast_rays(geometry: SceneGeometry, origins, directions) -> RayHits:
    """One-shot convenience: nearest receiver hit of each ray (see ``ReceiverTracer``)."""
    return ReceiverTracer(geometry)(origins, directions)
