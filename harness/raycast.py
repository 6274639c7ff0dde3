"""Exact ray casting against the scene's own triangles (Mitsuba's ray tracer).

The convergence tables compare each estimator's hit distance with the exact distance
along the same ray (v, r) to the receivers; this module provides that exact distance
from the very triangles both renderers were given (``scenes.geometry``).
"""

from __future__ import annotations

import numpy as np

from renderers.mitsuba._mi import load
from scenes.geometry import SceneGeometry, TriangleMesh

__all__ = ["RayHits", "ReceiverTracer", "cast_rays"]


def _mitsuba():
    """Mitsuba with its variant set (the renderer's one loader, ``llvm_ad_rgb``)."""
    return load()[0]


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


class MeshTracer:
    """Nearest hits against a list of meshes: ``tracer(origins, directions) -> RayHits``
    (``RayHits.receiver`` is then the index into ``meshes``)."""

    def __init__(self, meshes: list[TriangleMesh]):
        mi = _mitsuba()
        self._mi = mi
        self._scenes = [_mesh_scene(mi, mesh, f"mesh{i}") for i, mesh in enumerate(meshes)]

    def __call__(self, origins, directions) -> RayHits:
        """Cast rays from ``origins`` (N, 3) along ``directions`` (N, 3), metres.

        Directions are normalised here, so distances are in metres.
        """
        mi = self._mi
        o = np.asarray(origins, np.float64).reshape(-1, 3)
        d = np.asarray(directions, np.float64).reshape(-1, 3)
        if len(o) == 0:  # Dr.Jit aborts on zero-sized launches
            return RayHits(np.zeros(0), np.zeros(0, int), np.zeros((0, 3)))
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


class ReceiverTracer(MeshTracer):
    """Build once per geometry, then ``tracer(origins, directions) -> RayHits``."""

    def __init__(self, geometry: SceneGeometry):
        super().__init__([rec.mesh for rec in geometry.receivers])


def cast_rays(geometry: SceneGeometry, origins, directions) -> RayHits:
    """One-shot convenience: nearest receiver hit of each ray (see ``ReceiverTracer``)."""
    return ReceiverTracer(geometry)(origins, directions)


def camera_rays(camera) -> tuple[np.ndarray, np.ndarray]:
    """Primary rays through the pixel centres of a pinhole ``Camera``.

    Returns origins and unit directions, each (H·W, 3), rows in image order (row 0
    at the top). The field of view spans ``camera.fov_axis`` (Mitsuba's convention:
    horizontal for ``"x"``).
    """
    eye = np.asarray(camera.position, np.float64)
    forward = np.asarray(camera.look_at, np.float64) - eye
    forward /= np.linalg.norm(forward)
    right = np.cross(forward, camera.up)
    right /= np.linalg.norm(right)
    up = np.cross(right, forward)
    width, height = camera.resolution
    half = np.tan(np.radians(camera.fov) / 2)
    aspect = width / height
    half_x, half_y = (half, half / aspect) if camera.fov_axis == "x" else (half * aspect, half)
    x = ((np.arange(width) + 0.5) / width * 2 - 1) * half_x
    y = (1 - (np.arange(height) + 0.5) / height * 2) * half_y
    gx, gy = np.meshgrid(x, y)
    d = forward + gx[..., None] * right + gy[..., None] * up
    d = d.reshape(-1, 3)
    d /= np.linalg.norm(d, axis=1, keepdims=True)
    return np.broadcast_to(eye, d.shape).copy(), d
